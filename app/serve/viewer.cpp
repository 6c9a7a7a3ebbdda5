#include "serve/viewer.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "learn_common.hpp"
#include "learners/q_learning_steps.hpp"
#include "trials.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"
#include "plugins.hpp"

namespace mgrl::serve {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

struct ViewerAssets {
  /// The scenario opened once for every page: graph, behaviours, task and (when one serves)
  /// the policy bundle; session->policy empty: the policy controller is not offered.
  std::unique_ptr<Session> session;
  double meanOutDegree = 1;  ///< actions per state, for the online search's cost
  std::string note;          ///< shown on the page (no policy bundle, ...)
  ServeOptions options;      ///< what the server was started with (live retraining adds --set's)
  /// What eval counts as success (app::trialCriteria), which the page counts live, and
  /// its text ("contact of the fists within 0.15 m").
  std::vector<SuccessCriterion> criteria;
  std::string criteriaText;

  const StateActionModel& model() const { return session->model(); }
};

namespace {

// The online search expands about (actions per state)^horizon actions per decision; all
// avatars of a page decide within a few frames of each other. Above this many expansions
// per round, the world (and every page, on the one network thread) would stall.
constexpr double kSearchBudget = 1e6;

double searchCost(const ViewerAssets& assets, int horizon, std::size_t avatars) {
  return static_cast<double>(avatars) * std::pow(assets.meanOutDegree, horizon);
}

// The largest horizon the budget allows for `avatars` (at least 1).
int affordableHorizon(const ViewerAssets& assets, int wanted, std::size_t avatars) {
  int h = wanted;
  while (h > 1 && searchCost(assets, h, avatars) > kSearchBudget) --h;
  return h;
}

// Decisions timed (paper sec. 6.6 reports the runtime cost of a choice).
struct DecisionClock {
  double seconds = 0;
  std::size_t count = 0;
};

class TimedController final : public Controller {
 public:
  TimedController(std::unique_ptr<Controller> inner, DecisionClock& clock) : inner_(std::move(inner)), clock_(clock) {}
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng) override {
    const auto start = Clock::now();
    const std::size_t a = inner_->choose(s, e, rng);
    clock_.seconds += std::chrono::duration<double>(Clock::now() - start).count();
    ++clock_.count;
    return a;
  }
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng, std::span<const std::uint8_t> allowed) override {
    const auto start = Clock::now();
    const std::size_t a = inner_->choose(s, e, rng, allowed);
    clock_.seconds += std::chrono::duration<double>(Clock::now() - start).count();
    ++clock_.count;
    return a;
  }

 private:
  std::unique_ptr<Controller> inner_;
  DecisionClock& clock_;
};

// A page is sent at most this many hit messages per call of advance(); the others are
// only counted (a crowd of 2,000 lands over a thousand a second).
constexpr std::size_t kHitMessagesPerAdvance = 30;

}  // namespace

std::shared_ptr<const ViewerAssets> loadViewerAssets(const ServeOptions& options) {
  auto assets = std::make_shared<ViewerAssets>();
  assets->options = options;
  assets->options.log = {};  // never called from a retraining thread
  // With no --policy, a missing or stale default bundle is not an error: the search runs
  // and the page says how to train one. An explicit --policy must work.
  SessionNeeds needs;
  needs.policy = options.policy.empty() ? PolicyNeed::IfAvailable : PolicyNeed::Required;
  needs.policyDir = options.policy;
  assets->session = openSession(options, needs);
  const Session& session = *assets->session;
  if (!session.policyNote.empty())
    assets->note = fmt::format("No usable policy bundle ({}), so the online search runs instead. Train one with: "
                               "mgrl train {}",
                               session.policyNote, options.scenario.string());
  assets->criteria = app::trialCriteria(session.behaviors).first;
  std::vector<std::string> texts;
  for (const SuccessCriterion& c : assets->criteria) texts.push_back(c.describe());
  assets->criteriaText = fmt::format("{}", fmt::join(texts, ", or "));
  const StateActionModel& model = session.model();
  assets->meanOutDegree =
      std::max(1.0, static_cast<double>(model.actionCount()) / static_cast<double>(std::max<std::size_t>(1, model.stateCount())));
  return assets;
}

namespace {

// A behaviour retrained by one page (live retraining): its plugins built with the page's
// changed parameters, value iteration's table on them, and what evaluation said.
struct Retrained {
  Behavior behavior;
  std::shared_ptr<const Discretizer> refined;  ///< the learner's own grid, if it refined one
  QTable table;
  std::vector<double> vertices;  ///< (vertices, 3) positions, avatar frame
  json set;                      ///< the parameters changed, as the page sent them
  json curve = json::array();    ///< [updates, seconds, residual, mean residual]
  json before, after;            ///< Trials::summary of the policy without and with this table
  double trainSeconds = 0, totalSeconds = 0;
  std::uint64_t updates = 0;

  const Discretizer& grid() const { return refined ? *refined : *behavior.discretizer; }
};

// At most one retraining at a time on the whole server: it takes every core for a second
// or two, and the pages' worlds share them.
std::atomic<bool> gRetraining{false};

// What trials say about a retrained policy: this many trials of this much motion each.
constexpr std::size_t kRetrainTrials = 200;
constexpr double kRetrainTrialSeconds = 10;
// The tabulated problem and two tables of a retraining, at most.
constexpr double kRetrainBytes = 1e9;

double round3(double x) { return std::round(x * 1000) / 1000; }
json point3(const Eigen::Vector3d& p) { return json::array({round3(p.x()), round3(p.y()), round3(p.z())}); }

}  // namespace

struct ViewerSession::State {
  std::unique_ptr<World> world;
  std::string controller;
  int horizon = 3;
  std::vector<double> weights;
  double speed = 1, carry = 0;
  bool paused = false;
  int steps = 0;
  DecisionClock decisions;
  std::size_t eventsSeen = 0;
  std::deque<double> hitTimes;  ///< simulated times of the hits of the last 30 s
  // Successes as eval counts them (issue 17): each avatar's actions are followed by the
  // scenario's criteria from the target it decided on, as one trial that restarts at
  // each success. What the model says the action does, like eval's trials: the world's
  // pushes and foot locks are not seen.
  std::vector<std::vector<SuccessCriterion::Tracker>> trackers;  ///< per avatar, one per criterion
  std::vector<std::size_t> decisionsFollowed;                   ///< per avatar
  std::size_t successes = 0;
  std::deque<double> successTimes;  ///< simulated times of the successes of the last 30 s
  FrameWriter writer;
  double busySeconds = 0;       ///< simulating and encoding, since the last stats
  std::size_t busyFrames = 0;
  std::string adjustment;       ///< what the session changed on its own (scene note)
  int shown = -1;               ///< behaviour whose values are streamed (-1 none)
  std::size_t valuesFrame = 0;  ///< world frame of the last `values` message

  // The policy this page runs: the bundle's parts, a retrained behaviour's replaced.
  std::vector<PolicyPart> policy;
  std::vector<std::shared_ptr<const Retrained>> retrained;  ///< per behaviour; null: the bundle's

  // The learn panel: Q-learning a step at a time on one behaviour's problem.
  struct Lesson {
    int behavior = -1;
    std::shared_ptr<const Retrained> keep;  ///< the retrained plugins the lesson's problem uses
    std::unique_ptr<learners::QLearningSteps> steps;
    double rate = 0, carry = 0;  ///< steps per second while running
  };
  std::unique_ptr<Lesson> lesson;

  // A retraining under way on its own thread.
  struct Job {
    int behavior = -1;
    Clock::time_point started;
    std::atomic<bool> stop{false}, done{false};
    std::shared_ptr<Retrained> result;  ///< read once done
    std::string failure;                ///< set instead of a usable result
    std::thread thread;
  };
  std::unique_ptr<Job> job;

  ~State() {
    if (job && job->thread.joinable()) {
      job->stop = true;
      job->thread.join();
    }
  }
};

ViewerSession::ViewerSession(std::shared_ptr<const ViewerAssets> assets)
    : assets_(std::move(assets)), state_(std::make_unique<State>()) {
  for (const Behavior& b : assets_->session->behaviors) state_->weights.push_back(b.weight);
  state_->policy = assets_->session->policy;
  state_->retrained.resize(assets_->session->behaviors.size());
  state_->controller = assets_->session->policy.empty() ? "online_search" : "policy";
  rebuild(Mode::Target, 1);
}

ViewerSession::~ViewerSession() = default;

double ViewerSession::frameTime() const { return assets_->model().frameTime; }
std::size_t ViewerSession::avatars() const { return state_->world->avatarCount(); }

void ViewerSession::applyController() {
  State& s = *state_;
  const ViewerAssets& a = *assets_;
  if (s.controller == "online_search") {
    const int affordable = affordableHorizon(a, s.horizon, s.world->avatarCount());
    if (affordable < s.horizon) {
      s.adjustment = fmt::format("The online search's horizon was lowered from {} to {} actions for {} avatars (it "
                                 "would expand about {:.0f} actions per round of decisions; at most {:.0f} keep the "
                                 "world running).",
                                 s.horizon, affordable, s.world->avatarCount(),
                                 searchCost(a, s.horizon, s.world->avatarCount()), kSearchBudget);
      s.horizon = affordable;
    }
  }
  // The page's weights on the session's parts; the protocol's horizon is in actions only.
  ControllerParts parts = a.session->controllerParts(a.session->task.world.variety);
  parts.policy = s.policy;
  for (std::size_t i = 0; i < s.weights.size(); ++i) {
    if (i < parts.policy.size()) parts.policy[i].weight = s.weights[i];
    parts.search[i].weight = s.weights[i];
  }
  const ControllerChoice choice{s.controller, s.horizon, 0};
  DecisionClock* clock = &s.decisions;
  const std::vector<std::shared_ptr<const Retrained>> keep = s.retrained;  // the tables `parts` points into
  s.world->setControllerFactory([=]() -> std::unique_ptr<Controller> {
    (void)keep;
    return std::make_unique<TimedController>(makeController(choice, parts), *clock);
  });
}

void ViewerSession::rebuild(Mode mode, int avatars) {
  const ViewerAssets& a = *assets_;
  State& s = *state_;
  WorldSetup setup = a.session->worldSetup(static_cast<std::size_t>(avatars), 1, {"random"});  // replaced below
  setup.params.mode = mode == Mode::Target ? "targets" : "sparring";
  setup.threads = 1;  // every page on the server's one thread
  setup.poses = true;
  auto world = std::make_unique<World>(setup);
  s.world = std::move(world);
  mode_ = mode;
  s.adjustment.clear();
  applyController();
  s.carry = 0;
  s.eventsSeen = 0;
  s.hitTimes.clear();
  s.trackers.assign(s.world->avatarCount(), {});
  for (auto& list : s.trackers)
    for (const SuccessCriterion& c : a.criteria) list.emplace_back(c, a.model().frameTime);
  s.decisionsFollowed.assign(s.world->avatarCount(), 0);
  s.successes = 0;
  s.successTimes.clear();
  s.decisions = {};
  s.valuesFrame = 0;  // the new world counts frames from 0
  s.world->run(1);  // poses exist from the first frame on
  outbox_.push_back(scene());
}

std::string ViewerSession::scene() const {
  const ViewerAssets& a = *assets_;
  const State& s = *state_;
  json joints = json::array();
  for (const Joint& joint : a.session->graph.db.skeleton->joints())
    joints.push_back({{"name", joint.name}, {"parent", joint.parent}});
  json partners = json::array();
  for (std::size_t i = 0; i < s.world->avatarCount(); ++i) partners.push_back(s.world->partner(i));
  json behaviors = json::array();
  for (std::size_t i = 0; i < a.session->behaviors.size(); ++i) {
    json b = {{"name", a.session->behaviors[i].name},
              {"weight", s.weights[i]},
              {"activation", std::string(activationName(a.session->behaviors[i].activation))}};
    // The bundle's training record: its learner and curve (updates, seconds, residual,
    // mean residual), for the page's learning-curve view.
    const auto trained = a.session->bundle.behaviors.find(a.session->behaviors[i].name);
    if (const Retrained* r = s.retrained[i].get()) {
      // Retrained by this page: value iteration on the changed parameters.
      b["learner"] = "value_iteration";
      b["curve"] = r->curve;
      b["vertices"] = r->table.vertexCount();
      b["retrained"] = r->set;
    } else if (!a.session->policy.empty() && trained != a.session->bundle.behaviors.end()) {
      b["learner"] = trained->second.record.value("learner", std::string());
      b["curve"] = trained->second.record.value("curve", json::array());
      b["vertices"] = trained->second.table.vertexCount();
    }
    // The parameters live retraining may change: the reward's and the grid's numbers.
    json parameters = json::object();
    for (const char* section : {"reward", "discretizer"})
      for (const auto& [key, value] : a.session->behaviors[i].config[section].items())
        if (value.is_number()) parameters[fmt::format("{}.{}", section, key)] = value;
    if (const Retrained* r = s.retrained[i].get())
      for (const auto& [key, value] : r->set.items()) parameters[key] = value;
    b["parameters"] = parameters;
    // What eval counts as this behaviour's success (scenarios/README.md, "success:").
    b["success"] = a.session->behaviors[i].success ? json(a.session->behaviors[i].success->describe()) : json(nullptr);
    behaviors.push_back(std::move(b));
  }
  json controllers = json::array();
  if (!a.session->policy.empty()) controllers.push_back("policy");
  controllers.push_back("online_search");
  controllers.push_back("random");
  std::string note = a.note;
  if (!s.adjustment.empty()) note += (note.empty() ? "" : " ") + s.adjustment;
  return json{{"type", "scene"},
              {"mode", modeName(mode_)},
              {"avatars", s.world->avatarCount()},
              {"fps", 1.0 / a.model().frameTime},
              {"joints", joints},
              {"partners", partners},
              {"controller", s.controller},
              {"controllers", controllers},
              {"horizon", s.horizon},
              {"behaviors", behaviors},
              {"policy", a.session->policyDir.empty() ? json(nullptr) : json(a.session->policyDir.string())},
              {"note", note},
              {"scenario", a.session->scenario.name},
              {"limits",
               {{"crowd_min", Limits::kCrowdMin},
                {"crowd_max", Limits::kCrowdMax},
                {"message_bytes", Limits::kMessageBytes},
                {"messages_per_second", Limits::kMessagesPerSecond},
                {"horizon_max", Limits::kHorizonMax},
                {"weight_max", Limits::kWeightMax},
                {"speed_min", Limits::kSpeedMin},
                {"speed_max", Limits::kSpeedMax},
                {"target_reach", Limits::kTargetReach},
                {"target_height_max", Limits::kTargetHeightMax}}}}
      .dump();
}

int ViewerSession::behaviorIndex(std::string_view name) const {
  const auto& behaviors = assets_->session->behaviors;
  const auto it = std::find_if(behaviors.begin(), behaviors.end(), [&](const Behavior& b) { return b.name == name; });
  return it == behaviors.end() ? -1 : static_cast<int>(it - behaviors.begin());
}

std::string ViewerSession::behaviorNames() const {
  std::vector<std::string> names;
  for (const Behavior& b : assets_->session->behaviors) names.push_back(b.name);
  return fmt::format("{}", fmt::join(names, ", "));
}

void ViewerSession::handle(std::string_view text) {
  State& s = *state_;
  const ViewerAssets& a = *assets_;
  try {
    const ClientMessage message = parseClientMessage(text);
    if (const auto* mode = std::get_if<SetMode>(&message)) {
      rebuild(mode->mode, mode->avatars);
    } else if (const auto* move = std::get_if<MoveTarget>(&message)) {
      if (mode_ != Mode::Target)
        throw Error(fmt::format("move_target: expected target mode, found {} mode", modeName(mode_)));
      s.world->moveTarget(0, move->position);
    } else if (const auto* choice = std::get_if<SetController>(&message)) {
      if (choice->controller == "policy" && a.session->policy.empty())
        throw Error("controller.controller: expected online_search or random (this server has no policy bundle), "
                    "found \"policy\"");
      const std::string old = s.controller;
      const int oldHorizon = s.horizon;
      s.controller = choice->controller;
      if (choice->horizon > 0) s.horizon = choice->horizon;
      s.adjustment.clear();
      try {
        applyController();
      } catch (...) {
        s.controller = old;
        s.horizon = oldHorizon;
        applyController();
        throw;
      }
      outbox_.push_back(scene());
    } else if (const auto* set = std::get_if<SetWeights>(&message)) {
      std::vector<double> weights = s.weights;
      for (const auto& [name, weight] : set->weights) {
        const int i = behaviorIndex(name);
        if (i < 0)
          throw Error(fmt::format("weights.weights: expected behaviour names from {}, found \"{}\"", behaviorNames(),
                                  name));
        weights[static_cast<std::size_t>(i)] = weight;
      }
      s.weights = weights;
      applyController();
      outbox_.push_back(scene());
    } else if (const auto* pause = std::get_if<Pause>(&message)) {
      s.paused = pause->paused;
      s.carry = 0;
    } else if (std::holds_alternative<Step>(message)) {
      if (!s.paused) throw Error("step: expected a paused world (send {\"type\": \"pause\", \"paused\": true} first)");
      s.steps = std::min(s.steps + 1, 30);
    } else if (const auto* speed = std::get_if<SetSpeed>(&message)) {
      s.speed = speed->speed;
    } else if (const auto* show = std::get_if<ShowValues>(&message)) {
      if (show->behavior.empty()) {
        s.shown = -1;
      } else {
        const int i = behaviorIndex(show->behavior);
        if (i < 0)
          throw Error(fmt::format("values.behavior: expected one of {} or null, found \"{}\"", behaviorNames(),
                                  show->behavior));
        if (a.session->policy.empty())
          throw Error("values: expected a policy bundle to take values from; this server has none (mgrl train makes one)");
        s.shown = i;
        outbox_.push_back(values());
        s.valuesFrame = s.world->frame();
      }
    } else if (const auto* learnMessage = std::get_if<Learn>(&message)) {
      learn(*learnMessage);
    } else if (const auto* retrainMessage = std::get_if<Retrain>(&message)) {
      retrain(*retrainMessage);
    }
  } catch (const Error& e) {
    outbox_.push_back(json{{"type", "error"}, {"message", e.what()}}.dump());
  }
}

// The learn panel (issue 15): the paper's Q-learning (sec. 4.2) on one behaviour's problem
// with a table of the page's own, all zeros at the start, taken a step at a time so that
// each update can be looked at as the paper's Fig. 4 draws it.
void ViewerSession::learn(const Learn& message) {
  State& s = *state_;
  const ViewerAssets& a = *assets_;
  using Command = Learn::Command;
  if (message.command == Command::Start) {
    const int i = behaviorIndex(message.behavior);
    if (i < 0)
      throw Error(fmt::format("learn.behavior: expected one of {}, found \"{}\"", behaviorNames(), message.behavior));
    auto lesson = std::make_unique<State::Lesson>();
    lesson->behavior = i;
    lesson->keep = s.retrained[static_cast<std::size_t>(i)];
    const Behavior& b = lesson->keep ? lesson->keep->behavior : a.session->behaviors[static_cast<std::size_t>(i)];
    const Problem problem = b.problem(a.model());
    const double bytes = learners::QLearningSteps::tableBytes(problem);
    if (bytes > Limits::kLessonBytes)
      throw Error(fmt::format("learn: expected a lesson table of at most {} for one page, found {} for {} ({} vertices "
                              "x {} actions); choose a behaviour with a smaller grid",
                              app::humanBytes(Limits::kLessonBytes), app::humanBytes(bytes), b.name,
                              b.discretizer->vertexCount(), a.model().actionCount()));
    lesson->steps = std::make_unique<learners::QLearningSteps>(problem, message.budget, message.seed);
    s.lesson = std::move(lesson);
    outbox_.push_back(lessonMessage());
    return;
  }
  if (!s.lesson)
    throw Error("learn.command: expected a lesson started first ({\"type\": \"learn\", \"command\": \"start\", "
                "\"behavior\": ...}), found none");
  State::Lesson& lesson = *s.lesson;
  if (message.command == Command::Stop) {
    s.lesson.reset();
    outbox_.push_back(json{{"type", "lesson"}, {"behavior", nullptr}}.dump());
  } else if (message.command == Command::Run) {
    lesson.rate = message.rate;
    lesson.carry = 0;
  } else {
    if (lesson.steps->done())
      throw Error(fmt::format("learn: the lesson's budget of {} actions is spent; start a new one",
                              lesson.steps->budget()));
    const std::size_t n =
        std::min<std::uint64_t>(static_cast<std::uint64_t>(message.steps), lesson.steps->budget() - lesson.steps->updates());
    learners::QStep last;
    for (std::size_t k = 0; k < n; ++k) last = lesson.steps->step();
    outbox_.push_back(stepMessage(last, n));
  }
}

void ViewerSession::advanceLesson(double frames) {
  State& s = *state_;
  if (!s.lesson || s.lesson->rate <= 0) return;
  State::Lesson& lesson = *s.lesson;
  lesson.carry += frames * frameTime() * lesson.rate;
  // A late timer does not make the lesson race to catch up.
  const double most = std::max(1.0, 8 * frameTime() * Limits::kLearnRateMax);
  auto n = static_cast<std::size_t>(std::min(std::floor(lesson.carry), most));
  lesson.carry = std::min(lesson.carry - static_cast<double>(n), 1.0);
  n = std::min<std::uint64_t>(n, lesson.steps->budget() - lesson.steps->updates());
  if (n == 0) return;
  learners::QStep last;
  for (std::size_t k = 0; k < n; ++k) last = lesson.steps->step();
  if (lesson.steps->done()) lesson.rate = 0;
  outbox_.push_back(stepMessage(last, n));
}

std::string ViewerSession::lessonMessage() const {
  const State& s = *state_;
  const ViewerAssets& a = *assets_;
  const State::Lesson& lesson = *s.lesson;
  const learners::QLearningSteps& steps = *lesson.steps;
  const Behavior& b = lesson.keep ? lesson.keep->behavior : a.session->behaviors[static_cast<std::size_t>(lesson.behavior)];
  json vertices = json::array();
  for (std::size_t v = 0; v < b.discretizer->vertexCount(); ++v) vertices.push_back(point3(b.discretizer->vertexPosition(v)));
  return json{{"type", "lesson"},
              {"behavior", b.name},
              {"budget", steps.budget()},
              {"dimension", b.discretizer->dimension()},
              {"grid", b.discretizer->type()},
              {"vertices", vertices},
              {"states", a.model().stateCount()},
              {"actions", a.model().actionCount()},
              {"pairs", steps.table().vertexCount() * steps.table().actionCount()},
              {"gamma", b.reward->gamma()},
              {"state", steps.state()},
              {"target", point3(steps.target())},
              {"updates", steps.updates()},
              {"restarts", steps.restarts()},
              {"touched", steps.touched()}}
      .dump();
}

std::string ViewerSession::stepMessage(const learners::QStep& step, std::size_t taken) const {
  const State& s = *state_;
  const StateActionModel& model = assets_->model();
  const learners::QLearningSteps& steps = *s.lesson->steps;
  json vertices = json::array();
  for (const learners::QStepVertex& v : step.vertices)
    vertices.push_back({{"vertex", v.vertex},
                        {"position", point3(v.position)},
                        {"weight", v.weight},
                        {"reward", v.reward},
                        {"next", point3(v.next)},
                        {"next_inside", v.nextInside},
                        {"discount", v.discount},
                        {"future", v.future},
                        {"backup", v.backup},
                        {"before", v.before},
                        {"after", v.after}});
  // The action's root path on the floor, in the avatar's frame before it.
  json path = json::array();
  for (std::uint32_t k = model.actionFrameBegin[step.action]; k < model.actionFrameBegin[step.action + 1]; ++k)
    path.push_back({round3(model.frameRoot[3 * k]), 0, round3(model.frameRoot[3 * k + 1])});
  return json{{"type", "learn_step"},
              {"behavior", assets_->session->behaviors[static_cast<std::size_t>(s.lesson->behavior)].name},
              {"update", step.update},
              {"budget", steps.budget()},
              {"taken", taken},
              {"alpha", step.alpha},
              {"state", step.state},
              {"next_state", step.nextState},
              {"action", step.action},
              {"action_index", step.action - model.stateActionBegin[step.state]},
              {"actions", model.stateActionBegin[step.state + 1] - model.stateActionBegin[step.state]},
              {"frames", step.frames},
              {"target", point3(step.target)},
              {"target_next", point3(step.targetNext)},
              {"restarted", step.restarted},
              {"restarts", steps.restarts()},
              {"touched", steps.touched()},
              {"pairs", steps.table().vertexCount() * steps.table().actionCount()},
              {"done", steps.done()},
              {"path", path},
              {"vertices", vertices}}
      .dump();
}

// Live retraining (issue 15): value iteration on one behaviour with some of its reward's or
// grid's parameters changed, on a thread of its own; the page's avatar switches to the new
// table when it is done, and both policies are evaluated on the same trials.
void ViewerSession::retrain(const Retrain& message) {
  State& s = *state_;
  const ViewerAssets& a = *assets_;
  const int i = behaviorIndex(message.behavior);
  if (i < 0)
    throw Error(fmt::format("retrain.behavior: expected one of {}, found \"{}\"", behaviorNames(), message.behavior));
  if (a.session->policy.empty())
    throw Error("retrain: expected a policy bundle to start from; this server has none (mgrl train makes one)");
  if (s.job)
    throw Error(fmt::format("retrain: expected no retraining under way on this page, found one of {} (started {:.1f} s "
                            "ago)",
                            a.session->behaviors[static_cast<std::size_t>(s.job->behavior)].name,
                            std::chrono::duration<double>(Clock::now() - s.job->started).count()));
  const auto index = static_cast<std::size_t>(i);
  if (message.set.empty()) {  // back to the bundle's table
    s.retrained[index].reset();
    s.policy[index] = a.session->policy[index];
    applyController();
    outbox_.push_back(scene());
    outbox_.push_back(json{{"type", "retrain"}, {"behavior", message.behavior}, {"status", "reverted"}}.dump());
    return;
  }
  // The changed scenario, checked like `--set` on the command line: a wrong name or value
  // is refused here, before anything is trained.
  ServeOptions options = a.options;
  json set = json::object();
  for (const auto& [key, value] : message.set) {
    options.sets.push_back(fmt::format("behaviors.{}.{}={}", message.behavior, key, value));
    set[key] = value;
  }
  Scenario scenario = app::checkedScenario(options);
  std::vector<Behavior> built =
      buildBehaviors(scenario, app::plugins(), a.model(), a.session->graph.key, message.behavior);
  auto result = std::make_shared<Retrained>();
  result->behavior = std::move(built.front());
  result->set = set;
  const double bytes = GridModel::trainingBytes(a.model().actionCount(), result->behavior.discretizer->vertexCount());
  if (bytes > kRetrainBytes)
    throw Error(fmt::format("retrain: expected training to need at most {}, found {} for {} vertices x {} actions; "
                            "choose a coarser grid",
                            app::humanBytes(kRetrainBytes), app::humanBytes(bytes),
                            result->behavior.discretizer->vertexCount(), a.model().actionCount()));
  bool idle = false;
  if (!gRetraining.compare_exchange_strong(idle, true))
    throw Error("retrain: expected the server's one retraining slot to be free, found another page's retraining "
                "under way; try again when it ends");

  auto job = std::make_unique<State::Job>();
  job->behavior = i;
  job->started = Clock::now();
  job->result = result;
  // What the trials compare: this page's policy as it is, and with the new table.
  std::vector<PolicyPart> before = s.policy;
  for (std::size_t k = 0; k < before.size(); ++k) before[k].weight = s.weights[k];
  State::Job* j = job.get();
  std::shared_ptr<const ViewerAssets> assets = assets_;
  const std::vector<std::shared_ptr<const Retrained>> keep = s.retrained;  // `before` points into these
  job->thread = std::thread([j, assets, before, keep, result, index] {
    try {
      const StateActionModel& model = assets->model();
      const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
      const auto start = Clock::now();
      const Problem problem = result->behavior.problem(model);
      const GridModel grid = GridModel::build(problem, threads);
      const auto learner = app::plugins().learners.create(ConfigNode::parse("{type: value_iteration}", "retrain"));
      TrainResult trained = learner->train({problem, grid, nullptr, nullptr, threads, &j->stop});
      result->trainSeconds = std::chrono::duration<double>(Clock::now() - start).count();
      result->table = std::move(trained.table);
      result->refined = trained.grid;
      result->updates = trained.updates;
      for (const CurvePoint& p : trained.curve) result->curve.push_back({p.updates, p.seconds, p.residual, p.meanResidual});
      const Discretizer& g = result->grid();
      for (std::size_t v = 0; v < g.vertexCount(); ++v) {
        const Eigen::Vector3d p = g.vertexPosition(v);
        result->vertices.insert(result->vertices.end(), {p.x(), p.y(), p.z()});
      }
      // Success as the scenario defines it (its contact radius), on the same starts.
      // Targets at the scenario's world.target_height when it gives one, as eval's.
      const double height = assets->session->task.targetHeight(std::numeric_limits<double>::quiet_NaN());
      const app::Trials trials(model, assets->session->behaviors, assets->session->task, height, assets->session->scenario.path.string());
      std::vector<PolicyPart> after = before;
      after[index].grid = &g;
      after[index].table = &result->table;
      auto evaluate = [&](const std::vector<PolicyPart>& parts) {
        PolicyController controller(model, parts);
        return app::Trials::summary(trials.run([&](std::uint32_t node, const TargetState& e) { return controller.choose(node, e); },
                                               kRetrainTrials, kRetrainTrialSeconds, 1));
      };
      result->before = evaluate(before);
      result->after = evaluate(after);
      result->totalSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    } catch (const TrainInterrupted&) {
      j->failure = "interrupted";
    } catch (const std::exception& e) {
      j->failure = e.what();
    }
    (void)keep;
    gRetraining = false;
    j->done = true;
  });
  s.job = std::move(job);
  outbox_.push_back(json{{"type", "retrain"}, {"behavior", message.behavior}, {"status", "started"}, {"set", set}}.dump());
}

void ViewerSession::collectRetraining() {
  State& s = *state_;
  if (!s.job || !s.job->done) return;
  s.job->thread.join();
  const std::unique_ptr<State::Job> job = std::move(s.job);
  const auto index = static_cast<std::size_t>(job->behavior);
  const std::string& name = assets_->session->behaviors[index].name;
  if (!job->failure.empty()) {
    outbox_.push_back(json{{"type", "retrain"}, {"behavior", name}, {"status", "failed"}, {"message", job->failure}}.dump());
    return;
  }
  const std::shared_ptr<const Retrained> r = job->result;
  s.retrained[index] = r;
  s.policy[index].grid = &r->grid();
  s.policy[index].table = &r->table;
  applyController();
  outbox_.push_back(scene());
  outbox_.push_back(json{{"type", "retrain"},
                         {"behavior", name},
                         {"status", "done"},
                         {"set", r->set},
                         {"learner", "value_iteration"},
                         {"vertices", r->table.vertexCount()},
                         {"updates", r->updates},
                         {"train_seconds", r->trainSeconds},
                         {"seconds", std::chrono::duration<double>(Clock::now() - job->started).count()},
                         {"trials", kRetrainTrials},
                         {"before", r->before},
                         {"after", r->after}}
                        .dump());
}

void ViewerSession::followSuccess() {
  State& s = *state_;
  const World& world = *s.world;
  const StateActionModel& model = assets_->model();
  for (std::size_t i = 0; i < world.avatarCount(); ++i) {
    const World::Decision d = world.lastDecision(i);
    if (d.count == s.decisionsFollowed[i]) continue;
    s.decisionsFollowed[i] = d.count;
    std::uint32_t first = 0;  // the earliest offset any criterion is met at, as in eval's trials
    for (SuccessCriterion::Tracker& tracker : s.trackers[i])
      if (const std::uint32_t t = tracker.play(model, d.action, d.target); t > 0 && (first == 0 || t < first))
        first = t;
    if (first == 0) continue;
    ++s.successes;
    // The decision was made this frame: the success lands `first` frames on.
    s.successTimes.push_back(world.time() + static_cast<double>(first - 1) * model.frameTime);
    for (auto& tracker : s.trackers[i]) tracker = SuccessCriterion::Tracker(*tracker.criterion(), model.frameTime);
  }
}

bool ViewerSession::advance(double frames) {
  State& s = *state_;
  advanceLesson(frames);
  collectRetraining();
  std::size_t n = 0;
  if (s.paused) {
    n = static_cast<std::size_t>(s.steps);
    s.steps = 0;
  } else {
    s.carry += frames * s.speed;
    n = static_cast<std::size_t>(std::floor(s.carry));
    s.carry -= static_cast<double>(n);
    if (n > 8) {  // a late timer does not make the world race to catch up
      n = 8;
      s.carry = 0;
    }
  }
  if (n == 0) return false;
  const auto start = Clock::now();
  for (std::size_t k = 0; k < n; ++k) {  // frame by frame, so that no decision goes unseen
    s.world->run(1);
    followSuccess();
  }
  s.busySeconds += std::chrono::duration<double>(Clock::now() - start).count();
  s.busyFrames += n;
  const auto& events = s.world->events();
  std::size_t sent = 0;
  for (; s.eventsSeen < events.size(); ++s.eventsSeen) {
    const HitEvent& e = events[s.eventsSeen];
    s.hitTimes.push_back(e.time);
    if (sent++ >= kHitMessagesPerAdvance) continue;
    json hit = hitEventJson(e);
    hit["type"] = "hit";
    outbox_.push_back(hit.dump());
  }
  while (!s.hitTimes.empty() && s.hitTimes.front() < s.world->time() - 30) s.hitTimes.pop_front();
  while (!s.successTimes.empty() && s.successTimes.front() < s.world->time() - 30) s.successTimes.pop_front();
  // The teaching view follows avatar 0 five times a second of simulated time.
  if (s.shown >= 0 && s.world->frame() >= s.valuesFrame + 6) {
    outbox_.push_back(values());
    s.valuesFrame = s.world->frame();
  }
  return true;
}

const std::vector<std::uint8_t>& ViewerSession::frame() {
  State& s = *state_;
  const World& world = *s.world;
  const auto start = Clock::now();
  std::uint32_t targets = 0;
  for (std::size_t i = 0; i < world.avatarCount(); ++i) targets += world.partner(i) < 0;
  FrameHeader header;
  header.joints = static_cast<std::uint16_t>(assets_->session->graph.db.skeleton->jointCount());
  header.avatars = static_cast<std::uint32_t>(world.avatarCount());
  header.targets = targets;
  header.frame = static_cast<std::uint32_t>(world.frame());
  header.time = static_cast<float>(world.time());
  s.writer.begin(header);
  for (std::size_t i = 0; i < world.avatarCount(); ++i) s.writer.avatar(world.jointPositions(i));
  for (std::size_t i = 0; i < world.avatarCount(); ++i)
    if (world.partner(i) < 0) s.writer.target(static_cast<std::uint32_t>(i), world.target(i).centre());
  const auto& bytes = s.writer.finish();
  s.busySeconds += std::chrono::duration<double>(Clock::now() - start).count();
  return bytes;
}

// What the policy saw at avatar 0's last decision (paper sec. 5): at its state s, for every
// vertex v of the behaviour's grid (a 3-D grid's layer nearest the target's height), the
// value max_a Q(s, v, a) and the greedy action, placed around the avatar as it stood then;
// and the root path of the action it took.
std::string ViewerSession::values() const {
  const ViewerAssets& a = *assets_;
  const State& s = *state_;
  const auto shown = static_cast<std::size_t>(s.shown);
  const Retrained* retrained = s.retrained[shown].get();
  const Behavior& behavior = retrained ? retrained->behavior : a.session->behaviors[shown];
  const std::vector<double>& vertexPositions =
      retrained ? retrained->vertices : a.session->bundle.behaviors.at(behavior.name).vertices;
  const QTable& q = *s.policy[shown].table;
  const World::Decision d = s.world->lastDecision(0);
  const Eigen::Vector3d e = inverseTransformPoint(d.frame, s.world->aim(0));
  // A grid that also holds the target's heading (polar_velocity) repeats each position per
  // heading and speed layer: the viewer's target stands still, so show the speed-0 slice at
  // the heading nearest the decision's (a moving target's heading changes nothing at speed
  // 0; an opponent's facing, issue 17, does).
  const Discretizer& grid = *s.policy[shown].grid;
  const std::size_t vertices =
      grid.layerAxis() ? grid.axes()[0].vertices.size() * grid.axes()[1].vertices.size() : q.vertexCount();
  std::size_t offset = 0;
  if (grid.layerAxis() && grid.axes().size() == 3) {
    const std::vector<double>& headings = grid.axes()[2].vertices;
    double nearest = 10;
    for (std::size_t h = 0; h < headings.size(); ++h)
      if (const double gap = std::abs(std::remainder(headings[h] - d.target.heading, 2 * M_PI)); gap < nearest) {
        nearest = gap;
        offset = h * vertices;
      }
  }
  double level = vertexPositions.empty() ? 0 : vertexPositions[3 * offset + 1];
  for (std::size_t v = offset; v < offset + vertices; ++v)
    if (std::abs(vertexPositions[3 * v + 1] - e.y()) < std::abs(level - e.y())) level = vertexPositions[3 * v + 1];
  const std::size_t n = q.actionsOf(d.state);
  json points = json::array();
  double lo = 0, hi = 0;
  bool first = true;
  for (std::size_t v = offset; v < offset + vertices; ++v) {
    const double* p = &vertexPositions[3 * v];
    if (std::abs(p[1] - level) > 1e-6 || n == 0) continue;
    const float* row = q.row(d.state, v);
    const std::size_t best = static_cast<std::size_t>(std::max_element(row, row + n) - row);
    const Eigen::Vector3d w = transformPoint(d.frame, {p[0], p[1], p[2]});
    const double value = row[best];
    lo = first ? value : std::min(lo, value);
    hi = first ? value : std::max(hi, value);
    first = false;
    points.push_back({std::round(w.x() * 1000) / 1000, std::round(w.y() * 1000) / 1000, std::round(w.z() * 1000) / 1000,
                      value, best});
  }
  const StateActionModel& model = a.model();
  json path = json::array();
  for (std::uint32_t k = model.actionFrameBegin[d.action]; k < model.actionFrameBegin[d.action + 1]; ++k) {
    const Eigen::Vector3d w = transformPoint(d.frame, {model.frameRoot[3 * k], 0, model.frameRoot[3 * k + 1]});
    path.push_back({std::round(w.x() * 1000) / 1000, 0, std::round(w.z() * 1000) / 1000});
  }
  return json{{"type", "values"},
              {"behavior", behavior.name},
              {"avatar", 0},
              {"time", s.world->time()},
              {"state", d.state},
              {"actions", n},
              {"chosen", d.action - model.stateActionBegin[d.state]},
              {"height", level},
              {"target_inside", s.policy[shown].grid->inside(e)},
              {"v_min", lo},
              {"v_max", hi},
              {"points", points},
              {"path", path}}
      .dump();
}

std::string ViewerSession::stats(std::size_t framesSent, std::size_t framesDropped) {
  State& s = *state_;
  const World& world = *s.world;
  const double window = std::min(30.0, std::max(world.time(), 1.0));
  json j = {{"type", "stats"},
            {"time", world.time()},
            {"frame", world.frame()},
            {"paused", s.paused},
            {"speed", s.speed},
            {"hits", world.events().size()},
            {"hits_per_minute", static_cast<double>(s.hitTimes.size()) / window * 60.0},
            {"successes", s.successes},
            {"successes_per_minute", static_cast<double>(s.successTimes.size()) / window * 60.0},
            {"decisions", world.decisions()},
            {"decision_us", s.decisions.count ? s.decisions.seconds / static_cast<double>(s.decisions.count) * 1e6 : 0.0},
            {"server_ms_per_frame", s.busyFrames ? s.busySeconds / static_cast<double>(s.busyFrames) * 1e3 : 0.0},
            {"frames_sent", framesSent},
            {"frames_dropped", framesDropped},
            {"bytes_per_avatar_frame",
             avatarRecordBytes(assets_->session->graph.db.skeleton->jointCount())}};
  s.decisions = {};
  s.busySeconds = 0;
  s.busyFrames = 0;
  return j.dump();
}

std::vector<std::string> ViewerSession::takeOutbox() {
  std::vector<std::string> out;
  out.swap(outbox_);
  return out;
}

}  // namespace mgrl::serve
