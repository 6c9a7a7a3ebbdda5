#pragma once
/// \file
/// `mgrl eval`'s measurement as a library call (DESIGN.md sec. 5): a session's trials run
/// by a controller, with the random baseline on the same starts, the decision cost, and
/// for an opponent scenario the same controller against an avatar of the graph. The
/// command line and Python's Session.evaluate report the same figures from it.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/runtime/controller.hpp"
#include "mgrl/session/controllers.hpp"
#include "mgrl/session/session.hpp"

namespace mgrl {

struct EvalSettings {
  ControllerChoice controller;  ///< policy (greedy), online_search or random
  std::size_t trials = 100;
  double seconds = 10;  ///< motion per trial
  std::uint64_t seed = 1;
  double targetHeight = std::numeric_limits<double>::quiet_NaN();  ///< NaN: Task::targetHeight()'s default
  /// How the settings are called where they came from ("--trials" on the command line,
  /// "trials" in Python), for the messages.
  std::string trialsField = "--trials", secondsField = "--seconds";
};

/// Throws mgrl::Error ("--trials: expected a number of trials in [1, 10000000], found 0",
/// the controller's own checks against `controllers`, those the session is opened with)
/// unless `settings` are in range.
void checkEvalSettings(const ControllerRegistry& controllers, const EvalSettings& settings,
                       const ControllerFields& fields = {});

/// Runs the trials (mgrl/session/trials.hpp) of `session` with `settings`' controller, the
/// policy controller greedy on `policy` (eval measures the policy's own choice; the
/// session's bundle, or tables from elsewhere). Returns {"success_rate", "successes",
/// "mean_time_to_hit_s", "median_time_to_hit_s", "mean_return", "decisions",
/// "decisions_per_second", "controller", "trials", "seed", "seconds_per_trial", "success",
/// "target_height_m", "random_baseline" (not for random), "against_avatar" (an opponent
/// scenario), "horizon", "horizon_seconds", "mean_expanded_actions" (online_search)}.
/// Throws mgrl::Error for settings out of range or `policy` empty for the policy controller.
nlohmann::json evaluate(const Session& session, const std::vector<PolicyPart>& policy, const EvalSettings& settings);

}  // namespace mgrl
