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

#include "mgrl/core/error.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/simulate.hpp"

namespace mgrl {
struct Behavior;
}

namespace mgrl::app {


/// The session's options (scenario, --data, --cache, --set, the log) and the terminal's.
struct LearnOptions : SessionOptions {
  bool progressBar = false;       ///< draw a progress bar on stderr (a terminal)
};

/// Hears one behaviour's training beside the progress report (compare's snapshot
/// evaluator): progress and snapshots as a TrainObserver, and a record kept in the bundle.
class TrainListener : public TrainObserver {
 public:
  /// Kept in the behaviour's record in the policy bundle under "snapshots" (null: nothing).
  virtual nlohmann::json record() const { return nullptr; }
  /// Appended to the progress line (say, the last snapshot's success rate); "" nothing.
  virtual std::string status() const { return {}; }
};

/// Called once per behaviour about to be trained, with the scenario's behaviours and the
/// graph the tables are for (both outlive the listener); may return null.
using ListenerFactory = std::function<std::unique_ptr<TrainListener>(
    const Behavior& trained, const std::vector<Behavior>& all, const GraphResult& graph)>;

struct TrainOptions : LearnOptions {
  std::string behavior;        ///< only this one ("" every behaviour)
  std::filesystem::path out;   ///< policy bundle ("" the default in the cache)
  bool resume = false;         ///< continue from checkpoints left by a killed run
  double maxMemoryBytes = 1e18;  ///< refuse a behaviour whose training would need more
  /// The learning problem's model: "tabulated" (every transition stored, the fastest),
  /// "compact" (rewards only, a fifth of the memory, landings found per backup; same
  /// tables), or "auto": tabulated when it fits in maxMemoryBytes, else compact.
  std::string model = "auto";
  ListenerFactory listen;        ///< null: no listener
};

/// Trains, saves the policy bundle atomically and returns the --json report:
/// {"scenario", "policy", "graph_key", "behaviors": {NAME: {"learner", "updates", "seconds",
/// "updates_per_second", "final_residual", "table_bytes", ...}}}.
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

using mgrl::defaultPolicyDirectory;  // framework/session/policy_source.hpp

/// A run stopped by Ctrl-C or SIGTERM after saving what it could; the message says how to
/// continue. The command line exits with 130 for it.
class Interrupted : public Error {
 public:
  using Error::Error;
};

}  // namespace mgrl::app
