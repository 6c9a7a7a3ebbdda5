#pragma once
// Shared helpers for the test suite: where the real capture and the tiny test files are.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "mgrl/motion/motion_io.hpp"

// Both halves of a parser's error contract: the type (mgrl::ParseError) and the message
// (`source:line: expected ..., found ...`). Needs <catch2/catch.hpp> included first.
#define REQUIRE_PARSE_ERROR(expr, message)                     \
  do {                                                         \
    REQUIRE_THROWS_AS(expr, ::mgrl::ParseError);               \
    REQUIRE_THROWS_WITH(expr, ::Catch::Contains(message));     \
  } while (false)

namespace mgrl::test {

/// ../shared/mocap (or MGRL_DATA). Fails the test if it is missing: the integration tests
/// run on the real data, never silently skip it.
std::filesystem::path mocap();
/// tests/data.
std::filesystem::path testData();
/// Loads a file under mocap() in metres.
LoadedMotion loadMocap(const std::string& relative, const LoadOptions& options = {});

/// A small humanoid skeleton standing in Y-up, facing +Z, pelvis 1 m up, named `names`:
/// pelvis, spine, head, then per side (left, right) shoulder, forearm, hand, hip, knee,
/// ankle, toe. Hands and toes have end sites.
Skeleton humanoid(const std::vector<std::string>& names);
/// Names for humanoid() in CMU-like spelling.
std::vector<std::string> humanoidNames();

/// A fresh, empty directory under the system's temporary folder, removed with everything
/// in it when the object goes; `tag` and the process id keep parallel ctest runs apart.
struct TempDir {
  explicit TempDir(std::string_view tag);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::filesystem::path path;
};

}  // namespace mgrl::test
