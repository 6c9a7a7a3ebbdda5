#pragma once
// The benchmarks' command lines (all but mpi's, which takes a scenario and a behaviour),
// parsed by CLI11 as mgrl's are: a value out of range or an unknown option is refused with
// CLI11's message and exit status 2. Each takes --runs, those with a quick form --quick,
// and each adds its own options.
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

namespace mgrl::bench {

struct RunArgs {
  int runs = 0;        ///< timed runs; the benchmark reports their median
  bool quick = false;  ///< --quick: fewer runs (unless --runs says) and smaller loads
};

/// Parses `--runs N` (1 to 1000; default `runs`; given twice, the last counts), `--quick`
/// when `quickRuns` > 0 (then runs is quickRuns unless --runs is given, wherever it
/// stands: before this parser, `--runs 1 --quick` gave quickRuns) and what `more` adds. A
/// bad command line prints CLI11's message and exits with 2; --help prints the options
/// and exits with 0.
inline RunArgs parseRunArgs(int argc, char** argv, const std::string& about, int runs, int quickRuns = 0,
                            const std::function<void(CLI::App&)>& more = {}) {
  CLI::App app(about);
  RunArgs args{runs, false};
  CLI::Option* runsOption = app.add_option("--runs", args.runs, "timed runs; the median is reported")
                                ->check(CLI::Range(1, 1000))
                                ->take_last();
  if (quickRuns > 0) app.add_flag("--quick", args.quick, fmt::format("{} runs and smaller loads", quickRuns));
  if (more) more(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e) == 0 ? 0 : 2);
  }
  if (args.quick && runsOption->count() == 0) args.runs = quickRuns;
  return args;
}

/// `--data DIR` into `data`: the motion data folder (default: MGRL_DATA, else ../shared/mocap).
inline std::function<void(CLI::App&)> dataOption(std::filesystem::path& data) {
  return [&data](CLI::App& app) {
    app.add_option("--data", data, "motion data folder (default: MGRL_DATA, else ../shared/mocap)");
  };
}

}  // namespace mgrl::bench
