#pragma once
/// \file
/// Comparing learners (`mgrl compare`): several learners, several seeds, one behaviour, on
/// the same motion graph and the same evaluation trials, against a value-iteration
/// reference. Every run is trained by trainScenario(), as `mgrl train` trains it.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/training.hpp"

namespace mgrl {

/// The session's options (scenario, --data, --cache, --set, the log, the plug-ins) and what
/// to compare.
struct CompareOptions : SessionOptions {
  std::string behavior;                  ///< the behaviour whose learner varies
  std::vector<std::string> learners;     ///< registered learner names, no repeats
  std::vector<std::uint64_t> seeds{1};   ///< for learners with a `seed` parameter
  std::vector<std::string> learnerSets;  ///< LEARNER:KEY=VALUE
  std::size_t trials = 100;              ///< evaluation trials (the same starts for every run)
  double seconds = 10;                   ///< motion per trial
  /// Policies evaluated along each run's training, at about this many evenly spaced points
  /// (TrainObserver::snapshot); 0: none.
  std::size_t snapshots = 10;
  /// Trials per snapshot: the first of the same starts as the final evaluation; 0: the
  /// smaller of kDefaultSnapshotTrials and `trials`.
  std::size_t snapshotTrials = 0;
  /// KEY=VALUE: parameters of the behaviour's discretizer for the reference only (value
  /// iteration on a finer grid, say angles=40); empty: the behaviour's own grid.
  std::vector<std::string> referenceSets;
};

inline constexpr std::size_t kDefaultSnapshotTrials = 50;

/// Trains (or reuses from <cache>/compare/) and evaluates every learner x seed and returns
/// {"behavior", "reference", "runs": [...], "learners": {NAME: {"mean": {...}, "sd": {...},
/// "success_curve": [...]}}, "flags": [...]}; each run carries its residual "curve" and its
/// "snapshots" (success rate along training). A run's "nonzero_share" is the share of its
/// Q entries that are not zero (not of those updated). Figures its bundle's record lacks
/// ("train_seconds", "updates", "final_residual": a bundle written before they were
/// recorded) are null, as are the learner's mean and sd over them, never 0. Every mistake
/// in the options is reported before any training. `hooks`: the training's progress bar and
/// stop flag (log comes from options.log; listen is compare's own).
nlohmann::json compareLearners(const CompareOptions& options, const TrainHooks& hooks = {});

}  // namespace mgrl
