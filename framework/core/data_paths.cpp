#include "mgrl/core/data_paths.hpp"

#include <cstdlib>
#include <mutex>

namespace mgrl {

namespace {

std::mutex recordedMutex;
std::filesystem::path recorded;

}  // namespace

std::filesystem::path userDataDirectory() {
  if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "mgrl";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".local" / "share" / "mgrl";
  return {};
}

std::filesystem::path dataDirectory(const std::filesystem::path& explicitDir) {
  if (!explicitDir.empty()) return explicitDir;
  if (const char* env = std::getenv("MGRL_DATA"); env && *env) return env;
  // Where scripts/fetch_data.sh puts the capture, once it has.
  std::filesystem::path user = userDataDirectory();
  std::error_code error;
  if (!user.empty() && std::filesystem::is_directory(user, error)) return user;
  return std::filesystem::path(MGRL_SOURCE_DIR).parent_path() / "shared" / "mocap";
}

std::filesystem::path scenarioDataDirectory() {
  const std::lock_guard<std::mutex> lock(recordedMutex);
  return recorded.empty() ? dataDirectory() : recorded;
}

void recordScenarioDataDirectory(const std::filesystem::path& dir) {
  const std::lock_guard<std::mutex> lock(recordedMutex);
  recorded = dir;
}

}  // namespace mgrl
