// `mgrl compare`: the session stage's comparison (framework/session/compare.cpp), stopped
// by Ctrl-C and SIGTERM, and its text.
#include "compare_command.hpp"

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/numbers.hpp"
#include "mgrl/reports/compare_report.hpp"
#include "plural.hpp"
#include "train_support.hpp"

namespace mgrl::app {

using json = nlohmann::json;

json runCompare(const CompareOptions& options) {
  if (!options.report.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.report, ec);
    // The probe is `.mgrl-probe-PID`; a killed compare's is removed by the next one.
    if (ec || !folderTakesNewFiles(options.report, ".mgrl-probe-"))
      throw Error(fmt::format("--report {}: expected a folder where files can be written, found {}",
                              options.report.string(), ec ? ec.message() : std::string("it cannot be written")));
  }
  TrainHooks hooks;
  hooks.progressBar = options.progressBar;
  hooks.stop = &stopRequested;
  const StopSignals signals;  // Ctrl-C and SIGTERM raise stopRequested
  json report = compareLearners(options, hooks);
  if (!options.report.empty()) {
    writeCompareReport(options.report, report);
    report["report"] = (options.report / "index.html").string();
  }
  return report;
}

std::string compareText(const json& r) {
  std::string text = fmt::format("compare {} on {}: {}, {} trials each on the same starts; reference: {}\n",
                                 r["behavior"].get<std::string>(), r["scenario_name"].get<std::string>(),
                                 counted(r["runs"].size(), "run"), r["trials"].get<std::size_t>(),
                                 r["reference"]["description"].get<std::string>());
  text += fmt::format("{:<24} {:>14} {:>13} {:>13} {:>12} {:>10} {:>11} {:>11} {:>10}\n", "learner (mean ± sd)",
                      "success %", "time to hit s", "train s", "updates", "decide us", "V RMSE", "agreement %",
                      "non-zero %");
  auto cell = [](const json& l, const char* key, double scale, const char* format) {
    if (!l["mean"][key].is_number()) return std::string("n/a");
    return fmt::format(fmt::runtime(format), scale * l["mean"][key].get<double>(), scale * l["sd"][key].get<double>());
  };
  for (const auto& [name, l] : r["learners"].items())
    text += fmt::format("{:<24} {:>14} {:>13} {:>13} {:>12} {:>10} {:>11} {:>11} {:>10}\n", name,
                        cell(l, "success_rate", 100, "{:.1f} ± {:.1f}"), cell(l, "mean_time_to_hit_s", 1, "{:.2f} ± {:.2f}"),
                        cell(l, "train_seconds", 1, "{:.2f} ± {:.2f}"), cell(l, "updates", 1e-6, "{:.1f}M"),
                        cell(l, "decision_us", 1, "{:.2f}"), cell(l, "value_rmse", 1, "{:.3g}"),
                        cell(l, "greedy_agreement", 100, "{:.1f}"), cell(l, "nonzero_share", 100, "{:.1f}"));
  bool curves = false;
  for (const auto& [name, l] : r["learners"].items()) {
    if (l["success_curve"].empty()) continue;
    if (!curves)
      text += fmt::format("success % along training (mean over seeds; {} trials per snapshot), at updates:\n",
                          r["snapshot_trials"].get<std::size_t>());
    curves = true;
    std::string line = fmt::format("{:<24}", name);
    for (const json& p : l["success_curve"])
      line += fmt::format(" {:.0f}@{}", 100 * p[2].get<double>(), humanCount(p[0].get<double>()));
    text += line + "\n";
  }
  for (const json& flag : r["flags"]) text += "flag: " + flag.get<std::string>() + "\n";
  if (r.contains("report")) text += fmt::format("report: {}\n", r["report"].get<std::string>());
  return text;
}

}  // namespace mgrl::app
