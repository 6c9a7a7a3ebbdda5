#pragma once
// Shared by the runtime, adaptive and viewer benchmarks: the real boxing scenario with
// policies that take seconds, not minutes, to train.
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "builtin_plugins.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/training.hpp"

namespace mgrl::bench {

/// The options a benchmark's boxing session opens with and the bundle trained for it.
struct TrainedBoxing {
  SessionOptions options;
  std::filesystem::path policy;
};

/// Boxing with every behaviour trained as `mgrl train` trains it, into a scratch folder of
/// this process, `<tmp>/mgrl-bench-<tag>-<pid>` (the options' cache folder: the caller
/// removes it). `sets` default to value iteration for both behaviours (about two seconds).
inline TrainedBoxing trainBoxing(const std::string& tag,
                                 std::vector<std::string> sets = {"behaviors.approach.learner.type=value_iteration",
                                                                  "behaviors.hit.learner.type=value_iteration"}) {
  namespace fs = std::filesystem;
  const fs::path scratch = fs::temp_directory_path() / fmt::format("mgrl-bench-{}-{}", tag, ::getpid());
  TrainedBoxing trained;
  trained.options.scenario = fs::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing.yaml";
  trained.options.dataDir = dataDirectory("");
  trained.options.cacheDir = scratch;
  trained.options.sets = std::move(sets);
  trained.options.plugins = &builtinPlugins();
  trained.policy = scratch / "policy";
  const std::unique_ptr<const Session> session = openSession(trained.options, {.motion = false});
  TrainSettings settings;
  settings.out = trained.policy;
  trainScenario(*session, settings);
  return trained;
}

}  // namespace mgrl::bench
