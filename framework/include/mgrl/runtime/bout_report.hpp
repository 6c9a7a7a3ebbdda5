#pragma once
/// \file
/// Bout reports (docs/stats.md): which files make a bout (a folder, a pattern,
/// the SNU sparring capture), and the statistics of bouts, real or synthesized, per bout,
/// pooled and two groups compared, as JSON. `mgrl stats` prints them; Python and the
/// notebooks read the same report.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/learning/real_bouts.hpp"  // BoutFiles, snuBouts
#include "mgrl/runtime/bout_stats.hpp"

namespace mgrl {

/// One BOUT argument: a folder (every *.bvh in it; manifest.json and other files are
/// ignored) or a pattern with * or ? in its file name part. A relative argument is looked
/// up in the working folder first, then in `dataDir`. Throws mgrl::Error for a missing
/// folder, a folder without BVH files, a pattern matching nothing, wildcards in the folder
/// part.
BoutFiles resolveBout(const std::string& argument, const std::filesystem::path& dataDir);

struct StatsOptions {
  /// The bouts (with --compare: the real group).
  std::vector<std::string> bouts;
  bool snu = false;  ///< add every SNU bout (to the real group with --compare)
  bool compare = false;
  std::vector<std::string> synthetic;  ///< --compare: the bouts after `--`
  std::filesystem::path dataDir;
  StatsParams params;
  std::function<void(const std::string&)> log, warn;
};

/// Resolves, loads (everything first: a bad input fails before any measuring) and
/// measures; returns the report (docs/stats.md lists its keys).
nlohmann::json runStats(const StatsOptions& options);
/// One group's summary (a bout or a pool) as JSON.
nlohmann::json statsJson(const BoutStats& stats);
}  // namespace mgrl
