// `mgrl eval`'s measurement (evaluate.hpp): what runEval and Python's Session.evaluate run.
#include "mgrl/session/evaluate.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/session/trials.hpp"

namespace mgrl {

using json = nlohmann::json;

namespace {

// Makes a timed loop's result observable, so the compiler cannot drop the calls.
volatile std::size_t observed = 0;
void keepResult(std::size_t value) { observed = value; }

}  // namespace

void checkEvalSettings(const ControllerRegistry& controllers, const EvalSettings& settings,
                       const ControllerFields& fields) {
  checkControllerChoice(controllers, settings.controller, fields);
  if (settings.trials < 1 || settings.trials > 10'000'000)
    throw Error(fmt::format("{}: expected a number of trials in [1, 10000000], found {}", settings.trialsField,
                            settings.trials));
  if (!(settings.seconds > 0 && settings.seconds <= 3600))
    throw Error(fmt::format("{}: expected seconds of motion per trial in (0, 3600], found {}", settings.secondsField,
                            settings.seconds));
}

json evaluate(const Session& session, const std::vector<PolicyPart>& policy, const EvalSettings& settings) {
  checkEvalSettings(session.plugins().controllers, settings);
  const ControllerChoice& choice = settings.controller;
  const std::string& kind = choice.name;
  // The trials time the search's expansions and draw random actions themselves: eval
  // measures these three, not every registered controller.
  if (kind != "policy" && kind != "online_search" && kind != "random")
    throw Error(
        fmt::format("controller: expected policy, online_search or random (the controllers eval measures), "
                    "found {}",
                    quoteToken(kind)));
  if (kind == "policy" && policy.empty())
    throw Error("controller policy: expected trained tables for the scenario's behaviours, found none");
  const StateActionModel& model = session.model();
  // The target's height: the given one, else the scenario's world.target_height, else the
  // hitting points' centroid's.
  const Trials trials(model, session.behaviors, session.task, session.task.targetHeight(settings.targetHeight),
                      session.scenario.path.string(), session.plugins().conditions);
  // Greedy, without the world's variety. The online search moves the target as the
  // behaviours' environment model does (as trials do).
  std::unique_ptr<PolicyController> controller;
  if (!policy.empty()) controller = std::make_unique<PolicyController>(model, policy);
  OnlineSearchController search(model, *session.task.environment, session.search,
                                SearchHorizon{choice.horizon, choice.horizonSeconds}, session.task.gamma);
  std::size_t expanded = 0;
  auto choose = [&](const std::string& k, std::uint32_t s, const TargetState& e) -> std::size_t {
    if (k == "policy") return controller->choose(s, e);
    const std::size_t a = search.choose(s, e);
    expanded += search.expanded();
    return a;
  };
  // A trial's controller: none (uniformly random actions) for "random".
  auto chooserFor = [&](const std::string& k) {
    ChooseAction chooser;
    if (k != "random") chooser = [&, k](std::uint32_t s, const TargetState& e) { return choose(k, s, e); };
    return chooser;
  };
  auto run = [&](const std::string& k, std::vector<std::pair<std::uint32_t, TargetState>>* decisions) {
    return trials.run(chooserFor(k), settings.trials, settings.seconds, settings.seed, decisions);
  };

  std::vector<std::pair<std::uint32_t, TargetState>> decisions;
  TrialStats stats = run(kind, kind != "random" ? &decisions : nullptr);
  json report = Trials::summary(stats);
  if (kind == "online_search") {
    report["horizon"] = choice.horizon;
    report["horizon_seconds"] = choice.horizonSeconds;
    report["mean_expanded_actions"] = static_cast<double>(expanded) / static_cast<double>(std::max<std::size_t>(1, stats.decisions));
  }
  // Decision cost, measured apart from the simulation: replay the trials' decisions (at
  // least once, for at least 0.2 s).
  double perSecond = 0;
  const auto start = std::chrono::steady_clock::now();
  std::size_t sink = 0, calls = 0;
  if (kind != "random" && !decisions.empty()) {
    do {
      for (const auto& [s, e] : decisions) sink += choose(kind, s, e);
      calls += decisions.size();
    } while (since(start) < 0.2);
  } else {
    Rng rng(settings.seed);
    do {
      for (int i = 0; i < 100000; ++i) {
        const auto s = static_cast<std::uint32_t>(rng.below(model.stateCount()));
        sink += model.stateActionBegin[s] + rng.below(model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
      }
      calls += 100000;
    } while (since(start) < 0.2);
  }
  perSecond = static_cast<double>(calls) / since(start);
  keepResult(sink);
  report["decisions_per_second"] = perSecond;
  report["controller"] = kind;
  report["trials"] = settings.trials;
  report["seed"] = settings.seed;
  report["seconds_per_trial"] = settings.seconds;
  report["success"] = trials.successJson();
  report["target_height_m"] = trials.targetHeight();
  if (kind != "random") report["random_baseline"] = Trials::summary(run("random", nullptr));
  // An opponent scenario: the same controller against another avatar of the graph playing
  // the capture and throwing its own punches, not the environment model's opponent.
  if (trials.hasAvatarOpponent()) {
    auto against = [&](const std::string& k) {
      return Trials::summary(trials.runAgainstAvatar(chooserFor(k), settings.trials, settings.seconds, settings.seed));
    };
    json avatar = against(kind);
    if (kind != "random") avatar["random_baseline"] = against("random");
    report["against_avatar"] = avatar;
  }
  return report;
}

}  // namespace mgrl
