// `mgrl eval` (DESIGN.md sec. 5): runs a trained combined policy (or a random controller)
// from random starts against a static target and reports how often and how fast it hits.
#include <algorithm>
#include <cmath>
#include <iostream>

#include <fmt/format.h>

#include "learn_common.hpp"
#include "mgrl/session/session.hpp"
#include "plural.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/core/random.hpp"
#include "plugins.hpp"
#include "trials.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Makes a timed loop's result observable, so the compiler cannot drop the calls.
volatile std::size_t observed = 0;
void keepResult(std::size_t value) { observed = value; }

}  // namespace

json runEval(const EvalOptions& options) {
  const ControllerChoice choice{options.controller, options.horizon, options.horizonSeconds};
  checkControllerChoice(choice);
  if (options.trials < 1 || options.trials > 10'000'000)
    throw Error(fmt::format("--trials: expected a number of trials in [1, 10000000], found {}", options.trials));
  if (!(options.seconds > 0 && options.seconds <= 3600))
    throw Error(fmt::format("--seconds: expected seconds of motion per trial in (0, 3600], found {}", options.seconds));
  SessionNeeds needs;
  needs.policy = options.controller == "policy" ? PolicyNeed::Required : PolicyNeed::None;
  needs.policyDir = options.policy;
  needs.motion = false;  // trials need no poses
  const std::unique_ptr<Session> session = openSession(options, needs);
  const StateActionModel& model = session->model();
  const fs::path& dir = session->policyDir;

  // The target's height: --target-height, else the scenario's world.target_height, else
  // the hitting points' centroid's.
  const Trials trials(model, session->behaviors, session->task, session->task.targetHeight(options.targetHeight),
                      session->scenario.path.string());
  // eval measures the policy's own choice: greedy, without the world's variety. The online
  // search moves the target as the behaviours' environment model does (as trials do).
  PolicyController controller(model, session->policy);
  OnlineSearchController search(model, *session->task.environment, session->search,
                                SearchHorizon{options.horizon, options.horizonSeconds}, session->task.gamma);
  std::size_t expanded = 0;
  auto choose = [&](const std::string& kind, std::uint32_t s, const TargetState& e) -> std::size_t {
    if (kind == "policy") return controller.choose(s, e);
    const std::size_t a = search.choose(s, e);
    expanded += search.expanded();
    return a;
  };
  // A trial's controller: none (uniformly random actions) for "random".
  auto chooserFor = [&](const std::string& kind) {
    ChooseAction chooser;
    if (kind != "random") chooser = [&, kind](std::uint32_t s, const TargetState& e) { return choose(kind, s, e); };
    return chooser;
  };
  auto run = [&](const std::string& kind, std::vector<std::pair<std::uint32_t, TargetState>>* decisions) {
    return trials.run(chooserFor(kind), options.trials, options.seconds, options.seed, decisions);
  };

  std::vector<std::pair<std::uint32_t, TargetState>> decisions;
  const double startup = secondsSinceStart();
  TrialStats stats = run(options.controller, options.controller != "random" ? &decisions : nullptr);
  json report = Trials::summary(stats);
  if (options.controller == "online_search") {
    report["horizon"] = options.horizon;
    report["horizon_seconds"] = options.horizonSeconds;
    report["mean_expanded_actions"] = static_cast<double>(expanded) / static_cast<double>(std::max<std::size_t>(1, stats.decisions));
  }
  // Decision cost, measured apart from the simulation: replay the trials' decisions (at
  // least once, for at least 0.2 s).
  double perSecond = 0;
  if (options.controller != "random" && !decisions.empty()) {
    std::size_t sink = 0, calls = 0;
    const auto start = Clock::now();
    do {
      for (const auto& [s, e] : decisions) sink += choose(options.controller, s, e);
      calls += decisions.size();
    } while (since(start) < 0.2);
    perSecond = static_cast<double>(calls) / since(start);
    keepResult(sink);
  } else {
    const auto start = Clock::now();
    Rng rng(options.seed);
    std::size_t sink = 0, calls = 0;
    do {
      for (int i = 0; i < 100000; ++i) {
        const auto s = static_cast<std::uint32_t>(rng.below(model.stateCount()));
        sink += model.stateActionBegin[s] + rng.below(model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
      }
      calls += 100000;
    } while (since(start) < 0.2);
    perSecond = static_cast<double>(calls) / since(start);
    keepResult(sink);
  }
  report["decisions_per_second"] = perSecond;
  report["startup_seconds"] = startup;
  report["controller"] = options.controller;
  report["trials"] = options.trials;
  report["seed"] = options.seed;
  report["seconds_per_trial"] = options.seconds;
  report["success"] = trials.successJson();
  report["target_height_m"] = trials.targetHeight();
  if (options.controller == "policy") report["policy"] = dir.string();
  if (options.controller != "random") {
    report["random_baseline"] = Trials::summary(run("random", nullptr));
  }
  // An opponent scenario: the same controller against another avatar of the graph playing
  // the capture and throwing its own punches, not the environment model's opponent.
  if (trials.hasAvatarOpponent()) {
    auto against = [&](const std::string& kind) {
      return Trials::summary(trials.runAgainstAvatar(chooserFor(kind), options.trials, options.seconds, options.seed));
    };
    json avatar = against(options.controller);
    if (options.controller != "random") avatar["random_baseline"] = against("random");
    report["against_avatar"] = avatar;
  }
  return report;
}

std::string evalText(const json& r) {
  // "time to hit mean 3.40 s median 3.38 s", or "no hit" when no trial succeeded; "success"
  // instead of "hit" for a declared criterion, which the first line then states.
  const bool declared = r.contains("success") && r["success"].value("from", "") == "declared";
  const char* event = declared ? "success" : "hit";
  auto timeToHit = [&](const json& mean, const json& median) {
    if (mean.is_null()) return fmt::format("no {}", event);
    std::string text = fmt::format("time to {} mean {:.2f} s", event, mean.get<double>());
    if (!median.is_null()) text += fmt::format(" median {:.2f} s", median.get<double>());
    return text;
  };
  std::string text;
  if (declared) text += fmt::format("success: {}\n", r["success"]["text"].get<std::string>());
  text += fmt::format(
      "controller {}: {}, success rate {:.1f} %, {}, mean return {:.3f}, {}decisions/s\n",
      r["controller"].get<std::string>(), counted(r["trials"].get<std::size_t>(), "trial"),
      100 * r["success_rate"].get<double>(), timeToHit(r["mean_time_to_hit_s"], r["median_time_to_hit_s"]),
      r["mean_return"].get<double>(), humanCount(r["decisions_per_second"].get<double>()));
  if (r.contains("opponent_gap_m")) {
    const json& g = r["opponent_gap_m"];
    const json& f = r["opponent_facing_deg"];
    text += fmt::format("spacing to the opponent (pelvis to its ground point, every frame): median {:.2f} m, 5 % "
                        "under {:.2f} m, closest {:.2f} m; facing it within {:.0f} deg (median), 95 % within {:.0f} "
                        "deg\n",
                        g["median"].get<double>(), g["p5"].get<double>(), g["min"].get<double>(),
                        f["median"].get<double>(), f["p95"].get<double>());
  }
  if (r.contains("random_baseline")) {
    const json& b = r["random_baseline"];
    text += fmt::format("random baseline on the same starts: success rate {:.1f} %, {}, mean return {:.3f}\n",
                        100 * b["success_rate"].get<double>(), timeToHit(b["mean_time_to_hit_s"], json()),
                        b["mean_return"].get<double>());
  }
  if (r.contains("against_avatar")) {
    const json& a = r["against_avatar"];
    auto line = [](const json& x) {
      return fmt::format("success rate {:.1f} %, {:.2f} strikes reaching it a minute, bodies overlapping {:.1f} % of "
                         "the time, spacing median {:.2f} m",
                         100 * x["success_rate"].get<double>(), x.value("strikes_reached_per_minute", 0.0),
                         100 * x.value("bodies_overlapping", 0.0), x["opponent_gap_m"]["median"].get<double>());
    };
    text += fmt::format("against an avatar of the graph (playing the capture, punching at the avatar, {:g} s per "
                        "trial): {}",
                        r["seconds_per_trial"].get<double>(), line(a));
    if (a.contains("random_baseline")) text += fmt::format("\n  random actions against it: {}", line(a["random_baseline"]));
    text += "\n";
  }
  return text;
}

}  // namespace mgrl::app
