#pragma once
// Shared by the runtime and viewer benchmarks: the real boxing scenario with policies that
// take seconds, not minutes, to train.
#include <unistd.h>

#include <filesystem>
#include <string>

#include <fmt/format.h>

#include "app/learn_commands.hpp"
#include "mgrl/core/data_paths.hpp"

namespace mgrl::bench {

/// Boxing with both behaviours trained by value iteration (about two seconds) into a
/// scratch folder of this process, `<tmp>/mgrl-bench-<tag>-<pid>`: the options that trained
/// it, for loading it again.
inline app::TrainOptions trainBoxingByValueIteration(const std::string& tag) {
  namespace fs = std::filesystem;
  const fs::path scratch = fs::temp_directory_path() / fmt::format("mgrl-bench-{}-{}", tag, ::getpid());
  app::TrainOptions train;
  train.scenario = fs::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing.yaml";
  train.dataDir = dataDirectory("");
  train.cacheDir = scratch;
  train.out = scratch / "policy";
  train.sets = {"behaviors.approach.learner.type=value_iteration", "behaviors.hit.learner.type=value_iteration"};
  app::runTrain(train);
  return train;
}

}  // namespace mgrl::bench
