#include "learn_common.hpp"

#include <chrono>
#include <exception>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/learning/behavior.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/core/data_paths.hpp"
#include "plugins.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {
const std::chrono::steady_clock::time_point programStart = std::chrono::steady_clock::now();
}  // namespace

double secondsSinceStart() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - programStart).count();
}

Loaded load(const LearnOptions& options, Scenario scenario, bool motion, std::string graphKey) {
  GraphOptions graphOptions;
  graphOptions.key = std::move(graphKey);
  graphOptions.cacheDir = options.cacheDir;
  graphOptions.log = options.log;
  graphOptions.motion = motion;
  graphOptions.plugins = options.plugins;
  GraphResult graph = obtainGraph(scenario, graphOptions);
  return {std::move(scenario), std::move(graph)};
}



}  // namespace mgrl::app
