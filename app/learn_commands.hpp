#pragma once
/// \file
/// `mgrl train` and `mgrl eval` (DESIGN.md sec. 5).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "builtin_plugins.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/simulate.hpp"
#include "mgrl/session/training.hpp"

namespace mgrl {
struct Behavior;
}

namespace mgrl::app {

/// The session's options (scenario, --data, --cache, --set, the log, the built-in plug-ins)
/// and the terminal's.
struct LearnOptions : SessionOptions {
  LearnOptions() { plugins = &builtinPlugins(); }
  bool progressBar = false;       ///< draw a progress bar on stderr (a terminal)
};

/// `mgrl train`'s options: the session's and the terminal's, what to train and where
/// (TrainSettings), and who else hears it (compare's snapshot evaluator).
struct TrainOptions : LearnOptions, TrainSettings {
  ListenerFactory listen;  ///< null: no listener
};

/// Opens the scenario, trains it (trainScenario) with Ctrl-C and SIGTERM stopping it, and
/// returns the --json report (Trained::report).
nlohmann::json runTrain(const TrainOptions& options);
std::string trainText(const nlohmann::json& report);

struct EvalOptions : LearnOptions {
  std::filesystem::path policy;   ///< "" the default bundle of the scenario
  std::string controller = "policy";  ///< policy | online_search | random
  int horizon = 3;                ///< online_search: depth in actions
  double horizonSeconds = 0;      ///< online_search: > 0 searches this much motion instead
  std::size_t trials = 100;
  std::uint64_t seed = 1;
  double seconds = 10;            ///< motion per trial
  double targetHeight = std::numeric_limits<double>::quiet_NaN();  ///< NaN: the hitting points' centroid height
};

/// Runs the trials and returns {"success_rate", "mean_time_to_hit_s", "median_time_to_hit_s",
/// "mean_return", "decisions_per_second", ...}.
nlohmann::json runEval(const EvalOptions& options);
std::string evalText(const nlohmann::json& report);

struct SimulateOptions : LearnOptions {
  std::filesystem::path policy;  ///< "" the default bundle of the scenario
  SimulateSettings run;          ///< the command line's flags (mgrl/session/simulate.hpp)
};
/// Runs the world headless and returns {"avatars", "frames", "avatar_frames_per_second",
/// "hits", "hits_per_avatar_minute", ...}; writes the BVH files and events atomically.
nlohmann::json runSimulate(const SimulateOptions& options);
std::string simulateText(const nlohmann::json& report);

}  // namespace mgrl::app
