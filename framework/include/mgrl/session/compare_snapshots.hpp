#pragma once
/// \file
/// Compare's learning curves of success rate: a TrainListener that
/// evaluates the compared behaviour's table at each snapshot its learner hands out.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/session/compare.hpp"
#include "mgrl/session/graph_source.hpp"
#include "mgrl/session/trials.hpp"

namespace mgrl {

/// Evaluates the trained behaviour's table at each snapshot, with the other behaviours'
/// tables from the bundle at `shared` (as trained once for every run), on the first
/// `trials` of the final evaluation's trial starts (eval seed 1, options.seconds each): the
/// last snapshot, of the final table, scores as the final evaluation does on those trials.
/// record(): {"count", "trials", "seconds_per_trial", "seed", "columns": snapshotColumns(),
/// "points": [[updates, seconds, residual, success_rate, mean_time_to_hit_s, mean_return]...]}.
class SnapshotEvaluator final : public TrainListener {
 public:
  /// Throws mgrl::Error if `shared` lacks a current table of another behaviour.
  SnapshotEvaluator(const Behavior& trained, const std::vector<Behavior>& all, const GraphResult& graph,
                    const std::filesystem::path& shared, const CompareOptions& options, std::size_t count,
                    std::size_t trials);

  std::size_t snapshotCount() const override { return count_; }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override;
  nlohmann::json record() const override;
  std::string status() const override { return status_; }

 private:
  const std::vector<Behavior>& all_;
  const GraphResult& graph_;
  std::string trainedName_;
  std::size_t count_, trialCount_;
  double seconds_;
  Task task_;  ///< the world's target height and the behaviours' environment, as eval's
  Trials trials_;
  PolicyBundle bundle_;
  std::vector<PolicyPart> shared_;
  nlohmann::json points_ = nlohmann::json::array();
  std::string status_;
};

/// True if the policy bundle at `dir` holds a table of `behavior` but no snapshots of it
/// taken with these settings (a bundle from before snapshots were recorded, or taken with
/// others). Reads only the manifest; false when there is no such table (or no bundle).
bool lacksSnapshots(const std::filesystem::path& dir, const std::string& behavior, std::size_t count,
                    std::size_t trials, double seconds);

}  // namespace mgrl
