#include "mgrl/core/data_paths.hpp"

#include <cstdlib>

namespace mgrl {

std::filesystem::path dataDirectory(const std::filesystem::path& explicitDir) {
  if (!explicitDir.empty()) return explicitDir;
  if (const char* env = std::getenv("MGRL_DATA"); env && *env) return env;
  return std::filesystem::path(MGRL_SOURCE_DIR).parent_path() / "shared" / "mocap";
}

}  // namespace mgrl
