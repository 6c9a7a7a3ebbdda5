// `mgrl eval` (DESIGN.md sec. 5): runs a trained combined policy (or a random controller)
// from random starts against a static target and reports how often and how fast it hits.
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "learn_commands.hpp"
#include "mgrl/core/numbers.hpp"
#include "mgrl/session/evaluate.hpp"
#include "mgrl/session/session.hpp"
#include "plural.hpp"
#include "startup.hpp"

namespace mgrl::app {

using json = nlohmann::json;

json runEval(const EvalOptions& options) {
  EvalSettings settings;
  settings.controller = {options.controller, options.horizon, options.horizonSeconds};
  settings.trials = options.trials;
  settings.seconds = options.seconds;
  settings.seed = options.seed;
  settings.targetHeight = options.targetHeight;
  const ControllerRegistry& controllers = requirePlugins(options.plugins, "SessionOptions::plugins").controllers;
  checkEvalSettings(controllers, settings);
  const bool needsPolicy = controllers.find(options.controller)->needsPolicy;
  SessionNeeds needs;
  needs.policy = needsPolicy ? PolicyNeed::Required : PolicyNeed::None;
  needs.policyDir = options.policy;
  needs.motion = false;  // trials need no poses
  const std::unique_ptr<const Session> session = openSession(options, needs);
  const double startup = secondsSinceStart();
  json report = evaluate(*session, session->policy, settings);
  report["startup_seconds"] = startup;
  if (needsPolicy) report["policy"] = session->policyDir.string();
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
  if (r.contains("by_turn_rate")) {
    std::vector<std::string> parts;
    for (const json& t : r["by_turn_rate"])
      parts.push_back(fmt::format("{:+.0f} deg/s {:.1f} % of {}", t["turn_deg_s"].get<double>(),
                                  100 * t["success_rate"].get<double>(), t["trials"].get<std::size_t>()));
    text += fmt::format("by the target's turn rate: {}\n", fmt::join(parts, ", "));
  }
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
