#pragma once
// Shared helpers for the test suite: where the real capture and the tiny test files are.

#include <filesystem>
#include <string>

#include "mgrl/motion_io.hpp"

namespace mgrl::test {

/// ../shared/mocap (or MGRL_DATA). Fails the test if it is missing: the integration tests
/// run on the real data, never silently skip it.
std::filesystem::path mocap();
/// tests/data.
std::filesystem::path testData();
/// Loads a file under mocap() in metres.
LoadedMotion loadMocap(const std::string& relative, const LoadOptions& options = {});

}  // namespace mgrl::test
