#include "mgrl/core/launch.hpp"

#include <cstdlib>
#include <string>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

namespace {

// The variable's value as a whole number in [low, 1 << 24], or -1 if it is not set.
int wholeNumber(const char* name, int low) {
  const char* text = std::getenv(name);
  if (!text) return -1;
  const std::string s(text);
  std::size_t used = 0;
  long value = -1;
  try {
    value = std::stol(s, &used);
  } catch (...) {
    used = 0;
  }
  if (s.empty() || used != s.size() || value < low || value > (1L << 24))
    throw Error(fmt::format("{}: expected a whole number from {} to {} (set by an MPI launcher), found '{}'", name, low,
                            1L << 24, s));
  return static_cast<int>(value);
}

}  // namespace

LaunchedProcess launchedProcess() {
  static constexpr const char* kPairs[][2] = {{"OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE"},
                                              {"PMI_RANK", "PMI_SIZE"},
                                              {"PMIX_RANK", "SLURM_STEP_NUM_TASKS"}};
  for (const auto& pair : kPairs) {
    const int rank = wholeNumber(pair[0], 0);
    if (rank < 0) continue;
    const int size = wholeNumber(pair[1], 1);
    if (size < 0) continue;
    if (rank >= size)
      throw Error(fmt::format("{}: expected a rank below {}={}, found {}", pair[0], pair[1], size, rank));
    return {rank, size, true};
  }
  return {};
}

}  // namespace mgrl
