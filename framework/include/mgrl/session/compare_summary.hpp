#pragma once
/// \file
/// The figures `mgrl compare` reports for each run and each learner (compareLearners(),
/// Python's mgrl.compare): which metrics, in which order, and their mean and spread over a
/// learner's runs.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace mgrl {

/// The per-run metrics, in the order they are reported: (JSON key, label).
const std::vector<std::pair<std::string, std::string>>& compareMetrics();

/// The columns of a run's "snapshots" points.
const std::vector<std::string>& snapshotColumns();

/// Per learner, the mean and standard deviation of each compareMetrics() figure over its
/// runs (null where a run lacks it) and its success curve ([[updates, seconds, success
/// mean, success sd], ...] over its seeds, point by point; empty unless every run has as
/// many snapshots): the report's "learners", for `mgrl compare` and Python's mgrl.compare.
nlohmann::json learnerSummaries(const nlohmann::json& runs, const std::vector<std::string>& learners);

}  // namespace mgrl
