// The viewer's live retraining: value iteration on a thread of its own.
#include "serve/viewer_parts.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include <malloc.h>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "builtin_plugins.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/training.hpp"
#include "mgrl/session/trials.hpp"

namespace mgrl::serve {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// At most one retraining at a time on the whole server: it takes every core for a second
// or two, and the pages' worlds share them.
std::atomic<bool> gRetraining{false};
// Worker threads still running (detached: retrainings, worlds being built), for
// waitForWorkers().
std::mutex gRunningMutex;
std::condition_variable gRunningDone;
int gRunning = 0;

// What trials say about a retrained policy: this many trials of this much motion each.
constexpr std::size_t kRetrainTrials = 200;
constexpr double kRetrainTrialSeconds = 10;
// The tabulated problem and two tables of a retraining, at most.
constexpr double kRetrainBytes = 1e9;

// What a retraining trains: value iteration on the tabulated problem, within the server's
// limit.
TrainSettings retrainSettings(const Plugins& plugins) {
  static const std::shared_ptr<const Learner> valueIteration =
      plugins.learners.create(ConfigNode::parse("{type: value_iteration}", "retrain"));
  TrainSettings settings;
  settings.save = false;
  settings.learner = valueIteration;
  settings.maxMemoryBytes = kRetrainBytes;
  settings.model = "tabulated";
  settings.limitName = "the server's limit for a retraining";
  settings.limitRaisable = false;
  return settings;
}

// The retraining thread's work: the behaviour trained as every front end trains
// (trainBehavior), then both policies (`before`, and `before` with the new table) on the
// same trials. Checks the job's stop flag between stages (TrainInterrupted) and passes it to
// the training.
void trainAndEvaluate(std::atomic<bool>& stop, const ViewerAssets& assets, const std::vector<PolicyPart>& before,
                      Retrained& result, std::size_t index) {
  auto stopped = [&] {
    if (stop) throw TrainInterrupted(0, 0, false);
  };
  const StateActionModel& model = assets.model();
  const auto start = Clock::now();
  TrainHooks hooks;
  hooks.stop = &stop;
  Trained trained = trainBehavior(*assets.session, result.behavior, *result.scenario,
                                  retrainSettings(assets.session->plugins()), hooks);
  const std::string& name = result.behavior.name;
  PolicyBehavior& table = trained.bundle.behaviors.at(name);
  result.trainSeconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.table = std::move(table.table);
  if (const auto refined = trained.refined.find(name); refined != trained.refined.end())
    result.refined = refined->second;
  result.updates = trained.report["behaviors"][name]["updates"].get<std::uint64_t>();
  result.curve = table.record["curve"];
  const Discretizer& g = result.grid();
  for (std::size_t v = 0; v < g.vertexCount(); ++v) {
    const Eigen::Vector3d p = g.vertexPosition(v);
    result.vertices.insert(result.vertices.end(), {p.x(), p.y(), p.z()});
  }
  // Success as the scenario defines it (its contact radius), on the same starts.
  // Targets at the scenario's world.target_height when it gives one, as eval's.
  const double height = assets.session->task.targetHeight(std::numeric_limits<double>::quiet_NaN());
  const Trials trials(model, assets.session->behaviors, assets.session->task, height,
                      assets.session->scenario.path.string(), assets.session->plugins().conditions);
  std::vector<PolicyPart> after = before;
  after[index].grid = &g;
  after[index].table = &result.table;
  auto evaluate = [&](const std::vector<PolicyPart>& parts) {
    PolicyController controller(model, parts);
    return Trials::summary(
        trials.run([&](std::uint32_t node, const TargetState& e) { return controller.choose(node, e); }, kRetrainTrials,
                   kRetrainTrialSeconds, 1));
  };
  stopped();
  result.before = evaluate(before);
  stopped();
  result.after = evaluate(after);
  result.totalSeconds = std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

// Live retraining: value iteration on one behaviour with some of its reward's or
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
  // A whole-number parameter (the grid's counts) takes whole numbers as written: 3, not 3.0.
  for (const auto& [key, written] : message.fractional) {
    const std::size_t dot = key.find('.');
    const json& config = a.session->behaviors[index].config;
    const auto section = config.find(key.substr(0, dot));
    if (section == config.end()) continue;  // refused below, as on the command line
    const auto current = section->find(key.substr(dot + 1));
    if (current != section->end() && current->is_number_integer())
      throw Error(fmt::format("retrain.set[\"{}\"]: expected a whole number written without a decimal point or "
                              "exponent (the scenario has {}), found {}",
                              key, current->dump(), written));
  }
  json set = json::object();
  for (const auto& [key, value] : message.set) {
    options.sets.push_back(fmt::format("behaviors.{}.{}={}", message.behavior, key, value));
    set[key] = value;
  }
  Scenario scenario = checkedScenario(options);
  std::vector<Behavior> built =
      buildBehaviors(scenario, a.session->plugins(), a.model(), a.session->graph.key, message.behavior);
  auto result = std::make_shared<Retrained>();
  result->behavior = std::move(built.front());
  result->scenario = std::move(scenario);
  result->set = set;
  try {  // too large for the server: refused before anything is trained
    checkTrainingFits(result->behavior, a.model(), retrainSettings(a.session->plugins()));
  } catch (const Error& e) {
    throw Error(fmt::format("retrain: {}", e.what()));
  }
  bool idle = false;
  if (!gRetraining.compare_exchange_strong(idle, true))
    throw Error("retrain: expected the server's one retraining slot to be free, found another page's retraining "
                "under way; try again when it ends");

  auto job = std::make_shared<State::Job>();
  job->behavior = i;
  job->started = Clock::now();
  job->result = result;
  // What the trials compare: this page's policy as it is, and with the new table.
  std::vector<PolicyPart> before = s.policy;
  for (std::size_t k = 0; k < before.size(); ++k) before[k].weight = s.weights[k];
  std::shared_ptr<const ViewerAssets> assets = assets_;
  std::vector<std::shared_ptr<const Retrained>> keep = s.retrained;  // `before` points into these
  startWorker([j = job, assets, before, keep = std::move(keep), result, index]() mutable {
    try {
      trainAndEvaluate(j->stop, *assets, before, *result, index);
    } catch (const TrainInterrupted&) {
      j->failure = "interrupted";
    } catch (const std::exception& e) {
      j->failure = e.what();
    }
    const bool abandoned = j->stop;
    keep.clear();
    if (abandoned) {  // its page left: nobody will read it; its memory goes back now
      j->result.reset();
      result.reset();
      ::malloc_trim(0);
    }
    j->done = true;
    j.reset();
    assets.reset();
    gRetraining = false;
  });
  s.job = std::move(job);
  outbox_.push_back(
      json{{"type", "retrain"}, {"behavior", message.behavior}, {"status", "started"}, {"set", set}}.dump());
}

void startWorker(std::function<void()> work) {
  {
    const std::lock_guard lock(gRunningMutex);
    ++gRunning;
  }
  std::thread([work = std::move(work)]() mutable {
    work();
    work = nullptr;  // what it held goes before the server may stop
    const std::lock_guard lock(gRunningMutex);
    --gRunning;
    gRunningDone.notify_all();
  }).detach();
}

void waitForWorkers() {
  std::unique_lock lock(gRunningMutex);
  gRunningDone.wait(lock, [] { return gRunning == 0; });
}

void ViewerSession::collectRetraining() {
  State& s = *state_;
  if (!s.job || !s.job->done) return;
  const std::shared_ptr<State::Job> job = std::move(s.job);
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
  s.valuesSent.clear();  // the values view shows the new table at once
  applyController();
  outbox_.push_back(scene());
  outbox_.push_back(json{
      {"type", "retrain"},
      {"behavior", name},
      {"status", "done"},
      {"set", r->set},
      {"learner", "value_iteration"},
      {"vertices", r->table.vertexCount()},
      {"table_hash", tableHash(r->table)},
      {"updates", r->updates},
      {"train_seconds", r->trainSeconds},
      {"seconds", std::chrono::duration<double>(Clock::now() - job->started).count()},
      {"trials", kRetrainTrials},
      {"before", r->before},
      {"after",
       r->after}}.dump());
}

}  // namespace mgrl::serve
