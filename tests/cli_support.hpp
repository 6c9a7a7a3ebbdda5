#pragma once
// Shared by the tests that run the real `mgrl` binary (cli_learn_test.cpp,
// cli_simulate_test.cpp): shell words, captured streams and the --json report contract.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace mgrl::test {

/// A path as one shell word (the paths in tests hold no quote).
std::string shellWord(const std::filesystem::path& p);
/// The whole file, or "" if it cannot be read.
std::string readText(const std::filesystem::path& path);
/// `text` split at line ends.
std::vector<std::string> lines(const std::string& text);

/// What one run of the binary did.
struct Run {
  int status = -1;
  std::string out, err;

  std::string lastErrorLine() const;
  /// stdout as one JSON object, the whole of it; fails the test (showing stderr) if the run
  /// failed or printed anything else. Needs Catch2.
  nlohmann::json report() const;
};

/// Runs MGRL_BINARY with `arguments` (shell words) after `prefix` (e.g. "env -u NAME"),
/// stdin from /dev/null, capturing stdout and stderr through files in `streams`.
Run runMgrl(const std::string& arguments, const std::filesystem::path& streams, const std::string& prefix = "");

}  // namespace mgrl::test
