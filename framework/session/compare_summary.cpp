// The figures `mgrl compare` and Python's mgrl.compare report per learner
// (compare_summary.hpp); the report's files are written by mgrl/reports/compare_report.hpp.
#include "mgrl/session/compare_summary.hpp"

#include <cmath>

namespace mgrl {

using json = nlohmann::json;

const std::vector<std::pair<std::string, std::string>>& compareMetrics() {
  static const std::vector<std::pair<std::string, std::string>> metrics = {
      {"success_rate", "success"},
      {"mean_time_to_hit_s", "time to hit"},
      {"mean_return", "mean return"},
      {"train_seconds", "training time"},
      {"updates", "updates"},
      {"table_bytes", "table size"},
      {"decision_us", "decision time"},
      {"value_rmse", "V RMSE vs reference"},
      {"greedy_agreement", "greedy agreement"},
      {"nonzero_share", "Q entries non-zero"},
      {"cell_coverage", "grid cells walked"},
  };
  return metrics;
}

const std::vector<std::string>& snapshotColumns() {
  static const std::vector<std::string> columns = {
      "updates", "seconds", "residual", "success_rate", "mean_time_to_hit_s", "mean_return"};
  return columns;
}

namespace {

double meanOf(const std::vector<double>& xs) {
  double sum = 0;
  for (double x : xs) sum += x;
  return xs.empty() ? 0 : sum / static_cast<double>(xs.size());
}
double sdOf(const std::vector<double>& xs) {
  if (xs.size() < 2) return 0;
  const double m = meanOf(xs);
  double sum = 0;
  for (double x : xs) sum += (x - m) * (x - m);
  return std::sqrt(sum / static_cast<double>(xs.size() - 1));
}

// A learner's success rate along training, averaged over its seeds point by point:
// [[updates, seconds, success mean, success sd], ...]; empty unless every run has the same
// number of snapshots (q_learning's seeds take them at the same update counts).
json successCurve(const json& runs, const std::string& learner) {
  std::vector<const json*> curves;
  for (const json& r : runs)
    if (r["learner"] == learner) {
      if (!r["snapshots"].is_object()) return json::array();
      curves.push_back(&r["snapshots"]["points"]);
    }
  json out = json::array();
  if (curves.empty()) return out;
  for (const json* c : curves)
    if (c->size() != curves.front()->size()) return out;
  for (std::size_t i = 0; i < curves.front()->size(); ++i) {
    std::vector<double> updates, seconds, rates;
    for (const json* c : curves) {
      updates.push_back((*c)[i][0].get<double>());
      seconds.push_back((*c)[i][1].get<double>());
      rates.push_back((*c)[i][3].get<double>());
    }
    out.push_back({meanOf(updates), meanOf(seconds), meanOf(rates), sdOf(rates)});
  }
  return out;
}

}  // namespace

json learnerSummaries(const json& runs, const std::vector<std::string>& learners) {
  json out = json::object();
  for (const std::string& learner : learners) {
    json mean = json::object(), sd = json::object();
    for (const auto& [key, label] : compareMetrics()) {
      std::vector<double> xs;
      bool missing = false;
      for (const json& r : runs)
        if (r["learner"] == learner) {
          if (r[key].is_number())
            xs.push_back(r[key].get<double>());
          else
            missing = true;
        }
      mean[key] = missing || xs.empty() ? json(nullptr) : json(meanOf(xs));
      sd[key] = missing || xs.empty() ? json(nullptr) : json(sdOf(xs));
    }
    out[learner] = {{"mean", mean}, {"sd", sd}, {"success_curve", successCurve(runs, learner)}};
  }
  return out;
}

}  // namespace mgrl
