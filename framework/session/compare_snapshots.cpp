// Compare's snapshot evaluator (mgrl/session/compare_snapshots.hpp).
#include "mgrl/session/compare_snapshots.hpp"

#include <limits>

#include <fmt/format.h>

#include "mgrl/core/files.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/session/compare_summary.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/task.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;

SnapshotEvaluator::SnapshotEvaluator(const Behavior& trained, const std::vector<Behavior>& all,
                                     const GraphResult& graph, const fs::path& shared, const CompareOptions& options,
                                     std::size_t count, std::size_t trials)
    : all_(all),
      graph_(graph),
      trainedName_(trained.name),
      count_(count),
      trialCount_(trials),
      seconds_(options.seconds),
      // The final evaluation is eval's: targets at the scenario's world.target_height when
      // it gives one, so the snapshots' too.
      task_(makeTask(checkedScenario(options), all)),
      trials_(graph.model, all, task_, task_.targetHeight(std::numeric_limits<double>::quiet_NaN()),
              options.scenario.string(), options.plugins->conditions) {
  if (all.size() > 1) shared_ = policyParts(shared, all, graph, options, bundle_, trained.name);
}

void SnapshotEvaluator::snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) {
  // The parts in the scenario's order, as the final evaluation adds them up.
  std::vector<PolicyPart> parts;
  std::size_t next = 0;
  for (const Behavior& b : all_)
    parts.push_back(b.name == trainedName_
                        ? PolicyPart{grid ? grid : b.discretizer.get(), &table, b.weight, b.activation, b.stance}
                        : shared_[next++]);
  PolicyController controller(graph_.model, std::move(parts));
  const json result = Trials::summary(trials_.run(
      [&](std::uint32_t s, const TargetState& e) { return controller.choose(s, e); }, trialCount_, seconds_, 1));
  points_.push_back({point.updates, point.seconds, point.residual, result["success_rate"], result["mean_time_to_hit_s"],
                     result["mean_return"]});
  status_ = fmt::format("success {:.0f} % at snapshot {}", 100 * result["success_rate"].get<double>(), points_.size());
}

json SnapshotEvaluator::record() const {
  return {{"count", count_}, {"trials", trialCount_},        {"seconds_per_trial", seconds_},
          {"seed", 1},       {"columns", snapshotColumns()}, {"points", points_}};
}

bool lacksSnapshots(const fs::path& dir, const std::string& behavior, std::size_t count, std::size_t trials,
                    double seconds) {
  json record;
  try {
    record = json::parse(readFile(dir / "manifest.json")).at("behaviors").at(behavior).at("record");
  } catch (const std::exception&) {
    return false;  // no trained table of it here: training takes the snapshots anyway
  }
  try {
    const json& s = record.at("snapshots");
    return !(s.at("count") == count && s.at("trials") == trials && s.at("seconds_per_trial") == seconds &&
             s.at("seed") == 1 && s.at("points").is_array());
  } catch (const std::exception&) {
    return true;
  }
}

}  // namespace mgrl
