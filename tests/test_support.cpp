#include "test_support.hpp"

#include <catch2/catch.hpp>

#include "mgrl/data_paths.hpp"

namespace mgrl::test {

std::filesystem::path mocap() {
  const std::filesystem::path dir = dataDirectory();
  INFO("motion capture folder " << dir << " (set MGRL_DATA to move it)");
  REQUIRE(std::filesystem::is_directory(dir / "cmu"));
  return dir;
}

std::filesystem::path testData() { return MGRL_TEST_DATA_DIR; }

LoadedMotion loadMocap(const std::string& relative, const LoadOptions& options) {
  return loadMotion(mocap() / relative, options);
}

}  // namespace mgrl::test
