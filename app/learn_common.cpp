#include "learn_common.hpp"

#include <fmt/format.h>

#include "mgrl/behavior.hpp"
#include "mgrl/data_paths.hpp"
#include "plugins.hpp"

namespace mgrl::app {

std::string humanCount(double n) {
  if (n >= 1e9) return fmt::format("{:.2f} G", n / 1e9);
  if (n >= 1e6) return fmt::format("{:.2f} M", n / 1e6);
  if (n >= 1e3) return fmt::format("{:.1f} k", n / 1e3);
  return fmt::format("{:.0f} ", n);
}

std::string setFlags(const std::vector<std::string>& sets) {
  std::string text;
  for (const std::string& s : sets) text += fmt::format(" --set {}", s);
  return text;
}

// The scenario with its behaviours checked: every mistake that needs no graph is found
// before the graph is built or loaded.
Scenario checkedScenario(const LearnOptions& options) {
  Scenario scenario = loadScenario(options.scenario, dataDirectory(options.dataDir), options.sets);
  if (scenario.behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour (see scenarios/README.md), "
                       "found none");
  checkBehaviors(scenario, plugins());
  return scenario;
}


Loaded load(const LearnOptions& options, Scenario scenario) {
  GraphOptions graphOptions;
  graphOptions.cacheDir = options.cacheDir;
  graphOptions.log = options.log;
  GraphResult graph = obtainGraph(scenario, graphOptions);
  return {std::move(scenario), std::move(graph)};
}

}  // namespace mgrl::app
