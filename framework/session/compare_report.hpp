#pragma once
/// \file
/// What `mgrl compare` writes with --report DIR (issue 15): results.json, results.csv (one
/// row per run), curves.csv (every curve point of every run) and index.html, self-contained
/// (opens from disk, loads nothing), with SVG plots drawn here.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace mgrl {

/// The per-run metrics, in the order they are reported: (JSON key, label).
const std::vector<std::pair<std::string, std::string>>& compareMetrics();

/// The columns of a run's "snapshots" points.
const std::vector<std::string>& snapshotColumns();

/// Writes the four files into `dir` (each atomically). Throws mgrl::Error on I/O failure.
void writeCompareReport(const std::filesystem::path& dir, const nlohmann::json& report);

}  // namespace mgrl
