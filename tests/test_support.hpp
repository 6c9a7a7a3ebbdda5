#pragma once
// Shared helpers for the test suite: where the real capture and the tiny test files are.

#include <filesystem>
#include <functional>
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

// The source tree and the built program, as values rather than command-line definitions:
// only test_support.cpp is compiled with the paths (MGRL_TEST_PATH_*), so every other test
// file compiles to the same object in any checkout and a second checkout's build hits
// ccache (scripts/build.sh).
#ifndef MGRL_TEST_PATH_SOURCE
#define MGRL_SOURCE_DIR (::mgrl::test::sourceDirectory())
#define MGRL_BINARY (::mgrl::test::mgrlBinary())
#endif

namespace mgrl::test {

/// The repository root this suite was built from.
const char* sourceDirectory();
/// The `mgrl` program built beside the suite.
const char* mgrlBinary();

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

/// A folder shared by every test process of this build of the suite, for a result that
/// many tests need and none tests the making of (boxing trained by value iteration, say):
/// ctest runs each test case in a process of its own, so a fixture built per process is
/// built again for every test. The first caller runs `make(folder)` under an exclusive
/// lock (a second process waits for it), later callers get the finished folder. The
/// folders live in the test binary's build folder, under a name taken from the binary's
/// modification time: a rebuilt suite starts afresh, and removes the older ones.
std::filesystem::path sharedResult(const std::string& name,
                                   const std::function<void(const std::filesystem::path&)>& make);

}  // namespace mgrl::test
