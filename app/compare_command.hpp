#pragma once
/// \file
/// `mgrl compare`: the session stage's comparison of learners (mgrl/session/compare.hpp)
/// with the command line's plug-ins, stop signals and text.
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "builtin_plugins.hpp"
#include "mgrl/session/compare.hpp"

namespace mgrl::app {

/// The comparison's options with the built-in plug-ins, and the terminal's.
struct CompareOptions : mgrl::CompareOptions {
  CompareOptions() { plugins = &builtinPlugins(); }
  bool progressBar = false;  ///< draw a progress bar on stderr (a terminal)
  /// "" none; else the folder results.json, results.csv, curves.csv and index.html go to
  /// (writeCompareReport()), checked before anything trains.
  std::filesystem::path report;
};

/// compareLearners() with Ctrl-C and SIGTERM stopping the training under way, and the
/// report's files written (its "report" then names index.html).
nlohmann::json runCompare(const CompareOptions& options);
/// The report as `mgrl compare` prints it: a line per learner, the flags.
std::string compareText(const nlohmann::json& report);

}  // namespace mgrl::app
