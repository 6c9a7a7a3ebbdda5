// `mgrl eval` (DESIGN.md sec. 5): runs a trained combined policy (or a random controller)
// from random starts against a static target and reports how often and how fast it hits.
#include <algorithm>
#include <cmath>
#include <iostream>

#include <fmt/format.h>

#include "learn_common.hpp"
#include "plural.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/core/random.hpp"
#include "plugins.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Makes a timed loop's result observable, so the compiler cannot drop the calls.
volatile std::size_t observed = 0;
void keepResult(std::size_t value) { observed = value; }

struct TrialStats {
  std::size_t successes = 0, decisions = 0;
  std::vector<double> hitTimes;
  double returns = 0;
};

}  // namespace

json runEval(const EvalOptions& options) {
  if (options.controller != "policy" && options.controller != "random" && options.controller != "online_search")
    throw Error(fmt::format("--controller: expected one of: policy, online_search, random, found {}",
                            quoteToken(options.controller)));
  if (options.horizon < 1 || options.horizon > 8)
    throw Error(fmt::format("--horizon: expected a search depth in actions in [1, 8], found {}", options.horizon));
  if (!(options.horizonSeconds >= 0 && options.horizonSeconds <= 5))
    throw Error(fmt::format("--horizon-seconds: expected seconds of motion to search in [0, 5], found {}",
                            options.horizonSeconds));
  if (options.trials < 1 || options.trials > 10'000'000)
    throw Error(fmt::format("--trials: expected a number of trials in [1, 10000000], found {}", options.trials));
  if (!(options.seconds > 0 && options.seconds <= 3600))
    throw Error(fmt::format("--seconds: expected seconds of motion per trial in (0, 3600], found {}", options.seconds));
  Scenario scenario = checkedScenario(options);
  const fs::path dir = options.controller == "policy" ? resolvePolicy(options.policy, scenario, options) : fs::path();
  Loaded loaded = load(options, std::move(scenario));
  const StateActionModel& model = loaded.graph.model;
  std::vector<Behavior> behaviors = buildBehaviors(loaded.scenario, plugins(), model, loaded.graph.key);

  PolicyBundle bundle;
  std::vector<PolicyPart> parts;
  if (options.controller == "policy") parts = policyParts(dir, behaviors, loaded.graph, options, bundle);

  // The approach region: the first always-active behaviour's grid, sampled uniformly by area.
  const auto region = std::find_if(behaviors.begin(), behaviors.end(),
                                   [](const Behavior& b) { return b.activation == Activation::Always; });
  const Discretizer& regionGrid = *(region != behaviors.end() ? region : behaviors.begin())->discretizer;
  double reach = 0;
  for (const GridAxis& axis : regionGrid.axes())
    if (axis.name == "distance") reach = axis.vertices.back();
  if (!(reach > 0))
    throw Error(fmt::format("{}: expected a behaviour whose grid has a distance axis to place targets in, found none",
                            loaded.scenario.path.string()));
  // The target's height: given, else that of the effective hitting points' centroid (a
  // target at punching height, as the user's target in the paper's demo).
  const double targetHeight = std::isnan(options.targetHeight) ? model.centroid[1] : options.targetHeight;
  double contactRadius = 0.15;
  // A hit lands within the first hit reward's contact radius; returns are discounted with
  // the first behaviour's gamma.
  for (const Behavior& b : behaviors)
    if (b.reward->type() == "hit") {
      contactRadius = b.config["reward"].value("contact_radius", contactRadius);
      break;
    }
  const double gamma = behaviors.front().reward->gamma();
  const StaticTarget environment;
  PolicyController controller(model, parts);
  std::vector<SearchPart> searchParts;
  for (const Behavior& b : behaviors)
    searchParts.push_back({b.discretizer.get(), b.reward.get(), b.weight, b.activation});
  OnlineSearchController search(model, environment, searchParts, SearchHorizon{options.horizon, options.horizonSeconds},
                                gamma);
  std::size_t expanded = 0;
  auto choose = [&](const std::string& kind, std::uint32_t s, const Eigen::Vector3d& e) -> std::size_t {
    if (kind == "policy") return controller.choose(s, e);
    const std::size_t a = search.choose(s, e);
    expanded += search.expanded();
    return a;
  };

  auto run = [&](const std::string& kind, std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>* decisions) {
    Rng starts(options.seed), choices(options.seed ^ 0x5eed5eed5eedULL);
    TrialStats stats;
    const double limit = options.seconds / model.frameTime;
    for (std::size_t trial = 0; trial < options.trials; ++trial) {
      auto s = static_cast<std::uint32_t>(starts.below(model.stateCount()));
      Eigen::Vector3d e;
      do e = {(2 * starts.uniform() - 1) * reach, 0, (2 * starts.uniform() - 1) * reach};
      while (!regionGrid.inside(e));
      e.y() = targetHeight;
      double elapsed = 0, discount = 1, trialReturn = 0;
      bool hit = false;
      while (elapsed < limit && !hit) {
        std::size_t a;
        if (kind != "random") {
          if (decisions) decisions->emplace_back(s, e);
          a = choose(kind, s, e);
        } else {
          a = model.stateActionBegin[s] + choices.below(model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
        }
        ++stats.decisions;
        double reward = 0;
        for (const Behavior& b : behaviors) {
          if (b.activation == Activation::TargetInside && !b.discretizer->inside(e)) continue;
          reward += b.weight * b.reward->evaluate(model, a, e);
        }
        trialReturn += discount * reward;
        for (const ActionHit& h : model.hitsOf(a)) {
          const Eigen::Vector3d fist(h.x, h.y, h.z);
          if ((fist - e).norm() <= contactRadius) {
            hit = true;
            stats.hitTimes.push_back((elapsed + h.offset) * model.frameTime);
            break;
          }
        }
        const auto frames = static_cast<double>(model.actionLength(a));
        discount *= std::pow(gamma, frames);
        elapsed += frames;
        e = environment.next(model, a, e);
        s = model.actionTo[a];
      }
      stats.successes += hit;
      stats.returns += trialReturn;
    }
    return stats;
  };

  auto summarize = [&](TrialStats& stats) {
    std::sort(stats.hitTimes.begin(), stats.hitTimes.end());
    const std::size_t n = stats.hitTimes.size();
    double mean = 0;
    for (double t : stats.hitTimes) mean += t;
    json times = nullptr, median = nullptr;
    if (n > 0) {
      times = mean / static_cast<double>(n);
      median = n % 2 ? stats.hitTimes[n / 2] : (stats.hitTimes[n / 2 - 1] + stats.hitTimes[n / 2]) / 2;
    }
    return json{{"success_rate", static_cast<double>(stats.successes) / static_cast<double>(options.trials)},
                {"successes", stats.successes},
                {"mean_time_to_hit_s", times},
                {"median_time_to_hit_s", median},
                {"mean_return", stats.returns / static_cast<double>(options.trials)},
                {"decisions", stats.decisions}};
  };

  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> decisions;
  TrialStats stats = run(options.controller, options.controller != "random" ? &decisions : nullptr);
  json report = summarize(stats);
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
  report["controller"] = options.controller;
  report["trials"] = options.trials;
  report["seed"] = options.seed;
  report["seconds_per_trial"] = options.seconds;
  report["contact_radius_m"] = contactRadius;
  report["target_height_m"] = targetHeight;
  if (options.controller == "policy") report["policy"] = dir.string();
  if (options.controller != "random") {
    TrialStats baseline = run("random", nullptr);
    report["random_baseline"] = summarize(baseline);
  }
  return report;
}

std::string evalText(const json& r) {
  // "time to hit mean 3.40 s median 3.38 s", or "no hit" when no trial succeeded.
  auto timeToHit = [](const json& mean, const json& median) {
    if (mean.is_null()) return std::string("no hit");
    std::string text = fmt::format("time to hit mean {:.2f} s", mean.get<double>());
    if (!median.is_null()) text += fmt::format(" median {:.2f} s", median.get<double>());
    return text;
  };
  std::string text = fmt::format(
      "controller {}: {}, success rate {:.1f} %, {}, mean return {:.3f}, {}decisions/s\n",
      r["controller"].get<std::string>(), counted(r["trials"].get<std::size_t>(), "trial"),
      100 * r["success_rate"].get<double>(), timeToHit(r["mean_time_to_hit_s"], r["median_time_to_hit_s"]),
      r["mean_return"].get<double>(), humanCount(r["decisions_per_second"].get<double>()));
  if (r.contains("random_baseline")) {
    const json& b = r["random_baseline"];
    text += fmt::format("random baseline on the same starts: success rate {:.1f} %, {}, mean return {:.3f}\n",
                        100 * b["success_rate"].get<double>(), timeToHit(b["mean_time_to_hit_s"], json()),
                        b["mean_return"].get<double>());
  }
  return text;
}

}  // namespace mgrl::app
