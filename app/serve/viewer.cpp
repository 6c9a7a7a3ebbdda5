#include "serve/viewer_parts.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/q_learning_steps.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/trials.hpp"

namespace mgrl::serve {

namespace fs = std::filesystem;
using json = nlohmann::json;

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

// What a costly message of a kind not yet run on this server is taken to cost, s: as much
// as a page may spend at once (page_session.cpp's kAllowanceMax).
constexpr double kUnknownPrice = 0.1;

// A page is sent at most this many hit messages per call of advance(); the others are
// only counted (a crowd of 2,000 lands over a thousand a second).
constexpr std::size_t kHitMessagesPerAdvance = 30;

// The page's choices on `assets`' behaviours, as adopt() makes them: their weights, policy
// and bundle tables; the controller and horizon stay where the new scenario offers them.
PageChoices adoptedChoices(PageChoices page, const ViewerAssets& assets) {
  const Session& session = *assets.session;
  page.weights.clear();
  for (const Behavior& b : session.behaviors) page.weights.push_back(b.weight);
  page.policy = session.policy;
  page.retrained.assign(session.behaviors.size(), nullptr);
  if (page.controller.empty() || (page.controller == "policy" && session.policy.empty()))
    page.controller = session.policy.empty() ? "online_search" : "policy";
  return page;
}

}  // namespace

ViewerSession::ViewerSession(std::shared_ptr<const ViewerAssets> assets)
    : root_(std::move(assets)), state_(std::make_unique<State>()) {
  adopt(root_);
  // An opponent scene opens on the avatar and the opponent it was trained against (dodge's
  // scripted pursuer; spar_learned's partner playing a table); the others on the
  // paper's boxer and its target.
  if (!root_->session->task.opponent)
    rebuild(Mode::Target, 1);
  else
    rebuild(Mode::Sparring, 2);
}

void ViewerSession::adopt(std::shared_ptr<const ViewerAssets> assets) {
  State& s = *state_;
  PageChoices page = adoptedChoices(choices(), *assets);
  const std::shared_ptr<const ViewerAssets> old = std::exchange(assets_, std::move(assets));
  s.controller = std::move(page.controller);
  s.weights = std::move(page.weights);
  s.policy = std::move(page.policy);
  s.retrained = std::move(page.retrained);
  s.shown = -1;
  s.valuesSent.clear();
  if (s.lesson) {
    s.lesson.reset();
    outbox_.push_back(json{{"type", "lesson"}, {"behavior", nullptr}}.dump());
  }
  if (s.job) {  // its behaviour is the other scenario's: it is told to stop, and forgotten
    s.job->stop = true;
    outbox_.push_back(json{{"type", "retrain"},
                           {"behavior", old->session->behaviors[static_cast<std::size_t>(s.job->behavior)].name},
                           {"status", "failed"},
                           {"message", "stopped: the page switched to a mode that plays another scenario's behaviours"}}
                          .dump());
    s.job.reset();
  }
}

ViewerSession::~ViewerSession() = default;

double ViewerSession::frameTime() const { return assets_->model().frameTime; }
const ControllerRegistry& ViewerSession::controllers() const { return root_->session->plugins().controllers; }
std::size_t ViewerSession::avatars() const { return state_->world->avatarCount(); }

PageController pageController(const ViewerAssets& a, const PageChoices& page, std::size_t avatars) {
  PageController out;
  int horizon = page.horizon;
  if (page.controller == "online_search") {
    const int affordable = affordableHorizon(a, horizon, avatars);
    if (affordable < horizon) {
      out.adjustment = fmt::format(
          "The online search's horizon was lowered from {} to {} actions for {} avatars (it "
          "would expand about {:.0f} actions per round of decisions; at most {:.0f} keep the "
          "world running).",
          horizon, affordable, avatars, searchCost(a, horizon, avatars), kSearchBudget);
      horizon = affordable;
    }
  }
  // The page's weights on the session's parts; the protocol's horizon is in actions only.
  out.parts = a.session->controllerParts(a.session->task.world.variety);
  out.parts.policy = page.policy;
  for (std::size_t i = 0; i < page.weights.size(); ++i) {
    if (i < out.parts.policy.size()) out.parts.policy[i].weight = page.weights[i];
    out.parts.search[i].weight = page.weights[i];
  }
  out.choice = ControllerChoice{page.controller, horizon, 0};
  out.keep = page.retrained;
  return out;
}

PageChoices ViewerSession::choices() const {
  const State& s = *state_;
  return {s.controller, s.horizon, s.weights, s.policy, s.retrained};
}

PageChoices ViewerSession::choicesAfterAdopting(const ViewerAssets& assets) const {
  return &assets == assets_.get() ? choices() : adoptedChoices(choices(), assets);
}

void ViewerSession::applyController() {
  State& s = *state_;
  const PageController c = pageController(*assets_, choices(), s.world->avatarCount());
  if (!c.adjustment.empty()) {
    s.adjustment = c.adjustment;
    s.horizon = c.choice.horizon;
  }
  DecisionClock* clock = &s.decisions;
  const ControllerRegistry* registry = &controllers();  // the server's, outliving its pages
  s.world->setControllerFactory([c, clock, registry]() -> std::unique_ptr<Controller> {
    return std::make_unique<TimedController>(makeController(*registry, c.choice, c.parts), *clock);
  });
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
    if (a.session->behaviors[i].stance >= 0) b["stance"] = a.session->behaviors[i].stance;
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
  json offered = json::array();  // a controller that needs a policy only with a bundle
  for (const ControllerRegistry::Entry& entry : controllers().entries())
    if (!entry.needsPolicy || !a.session->policy.empty()) offered.push_back(entry.name);
  std::string note = a.note;
  if (mode_ != Mode::Target && !a.partnerNote.empty()) note += (note.empty() ? "" : " ") + a.partnerNote;
  if (!s.adjustment.empty()) note += (note.empty() ? "" : " ") + s.adjustment;
  return json{{"type", "scene"},
              {"mode", modeName(mode_)},
              {"avatars", s.world->avatarCount()},
              {"fps", 1.0 / a.model().frameTime},
              {"joints", joints},
              {"partners", partners},
              // What the second avatar of each pair plays when it is not the page's
              // controller: the scenario's scripted opponent (a dodge scene), or null.
              {"opponent", mode_ != Mode::Target && !a.session->partnerName(a.played).empty()
                               ? json(a.session->partnerName(a.played))
                               : json(nullptr)},
              {"controller", s.controller},
              {"controllers", offered},
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

namespace {

// What a message costs is counted in: a mode change in the avatars of the world it
// replaces and of the new one (`avatarsNow`), a lesson's steps in steps, a start in starts.
std::optional<std::pair<MessagePrices::Kind, double>> costOf(const ClientMessage& message, std::size_t avatarsNow,
                                                             bool lessonOn) {
  if (const auto* mode = std::get_if<SetMode>(&message))
    return std::pair(MessagePrices::Mode, static_cast<double>(avatarsNow + static_cast<std::size_t>(mode->avatars)));
  if (const auto* learn = std::get_if<Learn>(&message)) {
    if (learn->command == Learn::Command::Start) return std::pair(MessagePrices::LessonStart, 1.0);
    if (learn->command == Learn::Command::Step && lessonOn)
      return std::pair(MessagePrices::LessonSteps, static_cast<double>(learn->steps));
    return std::nullopt;
  }
  if (std::holds_alternative<Retrain>(message)) return std::pair(MessagePrices::Retrain, 1.0);
  return std::nullopt;
}

}  // namespace

double ViewerSession::price(std::string_view text) const {
  try {
    const auto cost = costOf(parseClientMessage(text, controllers().names()), avatars(), state_->lesson != nullptr);
    // A kind this server has not run yet is taken to cost the most a page may spend at once.
    return cost ? root_->prices.price(cost->first, cost->second, kUnknownPrice) : 0.0;
  } catch (const Error&) {
    return 0;  // refused at once when handled
  }
}

void ViewerSession::handle(std::string_view text) {
  try {
    const ClientMessage message = parseClientMessage(text, controllers().names());
    const auto began = Clock::now();
    const auto cost = costOf(message, avatars(), state_->lesson != nullptr);
    handle(message);
    if (cost)
      root_->prices.learn(cost->first, cost->second, std::chrono::duration<double>(Clock::now() - began).count());
  } catch (const Error& e) {
    outbox_.push_back(json{{"type", "error"}, {"message", e.what()}}.dump());
  }
}

void ViewerSession::handle(const ClientMessage& message) {
  State& s = *state_;
  const ViewerAssets& a = *assets_;
  if (const auto* mode = std::get_if<SetMode>(&message)) {
    rebuild(mode->mode, mode->avatars);
  } else if (const auto* move = std::get_if<MoveTarget>(&message)) {
    if (mode_ != Mode::Target)
      throw Error(fmt::format("move_target: expected target mode, found {} mode", modeName(mode_)));
    s.world->moveTarget(0, move->position);
  } else if (const auto* choice = std::get_if<SetController>(&message)) {
    // The protocol took only the registry's names.
    if (controllers().find(choice->controller)->needsPolicy && a.session->policy.empty())
      throw Error(fmt::format("controller.controller: expected {} (this server has no policy bundle), found \"{}\"",
                              controllerAlternatives(controllers(), true), choice->controller));
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
        throw Error(
            fmt::format("weights.weights: expected behaviour names from {}, found \"{}\"", behaviorNames(), name));
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
        throw Error(
            fmt::format("values.behavior: expected one of {} or null, found \"{}\"", behaviorNames(), show->behavior));
      if (a.session->policy.empty())
        throw Error(
            "values: expected a policy bundle to take values from; this server has none (mgrl train makes one)");
      s.shown = i;
      s.valuesSent = values();
      outbox_.push_back(s.valuesSent);
      s.valuesFrame = s.world->frame();
    }
  } else if (const auto* learnMessage = std::get_if<Learn>(&message)) {
    learn(*learnMessage);
  } else if (const auto* retrainMessage = std::get_if<Retrain>(&message)) {
    retrain(*retrainMessage);
  }
}

bool ViewerSession::advance(double frames, double sliceSeconds) {
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
    if (k + 1 < n && std::chrono::duration<double>(Clock::now() - start).count() >= sliceSeconds) {
      s.framesShed += n - k - 1;
      n = k + 1;
      s.carry = 0;
    }
  }
  s.busySeconds += std::chrono::duration<double>(Clock::now() - start).count();
  s.busyFrames += n;
  const auto& events = s.world->events();
  std::size_t sent = 0;
  for (; s.eventsSeen < events.size(); ++s.eventsSeen) {
    const HitEvent& e = events[s.eventsSeen];
    if (!e.blocked) s.hitTimes.push_back(e.time);
    if (sent++ >= kHitMessagesPerAdvance) continue;
    json hit = hitEventJson(e);
    hit["type"] = "hit";
    outbox_.push_back(hit.dump());
  }
  while (!s.hitTimes.empty() && s.hitTimes.front() < s.world->time() - 30) s.hitTimes.pop_front();
  while (!s.successTimes.empty() && s.successTimes.front() < s.world->time() - 30) s.successTimes.pop_front();
  // The teaching view follows avatar 0 five times a second of simulated time.
  // Sent only when they changed: a retrained grid's values are 181 KB.
  if (s.shown >= 0 && s.world->frame() >= s.valuesFrame + 6) {
    std::string now = values();
    if (now != s.valuesSent) {
      outbox_.push_back(now);
      s.valuesSent = std::move(now);
    }
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

std::vector<std::string> ViewerSession::takeOutbox() {
  std::vector<std::string> out;
  out.swap(outbox_);
  return out;
}

}  // namespace mgrl::serve
