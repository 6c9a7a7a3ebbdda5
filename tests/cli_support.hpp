#pragma once
// Shared by the tests that run the real `mgrl` binary (cli_learn_test.cpp,
// cli_simulate_test.cpp): shell words, captured streams and the --json report contract.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

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

/// A fresh folder per CLI test (cache, bundles, outputs), removed at the end even when the
/// test fails; the command-specific sandboxes add their runs on top.
class CliSandbox {
 public:
  explicit CliSandbox(std::string_view tag) : temp_(tag) {}
  const std::filesystem::path& dir() const { return temp_.path; }
  std::filesystem::path cache() const { return dir() / "cache"; }
  std::filesystem::path path(const std::string& name) const { return dir() / name; }
  /// " --cache <sandbox>/cache --data <mocap>".
  std::string where() const { return " --cache " + shellWord(cache()) + " --data " + shellWord(mocap()); }

 private:
  TempDir temp_;
};

}  // namespace mgrl::test
