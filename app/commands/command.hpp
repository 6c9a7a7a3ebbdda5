#pragma once
/// \file
/// The subcommands of `mgrl` (DESIGN.md sec. 5), one small object each: its constructor
/// puts the subcommand and its options on the command line, run() does the work once the
/// line is parsed. Adding a command is one new class plus one line in makeCommands()
/// (command.cpp). main.cpp parses, runs the parsed one and maps errors to exit codes.
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "learn_commands.hpp"

namespace mgrl::app::cli {

/// What several commands share: --json, and a scenario's path, --data and --cache (only
/// one command is parsed, so one set serves them all).
struct Common {
  bool json = false;
  std::string scenario, dataDir, cacheDir;
  /// `mgrl stats --compare REAL... -- SYNTH...`: what followed `--`, cut off before parsing
  /// (CLI11 would fold it into the positionals).
  std::vector<std::string> afterDash;
  bool dash = false;
};

class Command {
 public:
  explicit Command(CLI::App* sub) : sub_(sub) {}
  virtual ~Command() = default;
  Command(const Command&) = delete;
  Command& operator=(const Command&) = delete;

  const CLI::App& subcommand() const { return *sub_; }
  bool parsed() const { return sub_->parsed(); }
  /// Throws mgrl::Error (one line for stderr) or mgrl::app::Interrupted.
  virtual void run(const Common& common) = 0;

 protected:
  CLI::App* sub_;
};

/// A command on a scenario that opens a session (train, eval, simulate, compare, serve).
/// The constructor adds SCENARIO; the subclass adds its own options, then calls
/// addSessionOptions() for --set, --json (when it prints a report), --data and --cache.
/// run() fills the session's options from the shared ones and calls runSession().
class SessionCommand : public Command {
 public:
  void run(const Common& common) final;

 protected:
  SessionCommand(CLI::App* sub, Common& common, const std::string& scenarioHelp = "Scenario YAML file");
  void addSessionOptions(SessionOptions& options, Common& common, bool json,
                         const std::string& setHelp = "Override a scenario key (repeatable)");
  virtual void runSession(const Common& common) = 0;

 private:
  SessionOptions* session_ = nullptr;
};

/// Every command, in the order `mgrl --help` lists them.
std::vector<std::unique_ptr<Command>> makeCommands(CLI::App& app, Common& common);

/// The factories, one per file of app/commands/.
std::unique_ptr<Command> inspectCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> initCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> graphCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> trainCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> evalCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> simulateCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> compareCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> serveCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> statsCommand(CLI::App& app, Common& common);
std::unique_ptr<Command> listCommand(CLI::App& app, Common& common);

/// The session's options (scenario, --data, --cache, the log) from the shared ones, for
/// every command that opens a session.
void fillSession(SessionOptions& options, const Common& common);

/// --json: the report as one JSON object on stdout; else the text.
inline void print(const Common& common, const nlohmann::json& report, const std::string& text) {
  if (common.json)
    std::cout << report.dump(2) << '\n';
  else
    std::cout << text;
}

/// The log every command writes to stderr: "mgrl: MESSAGE".
inline void logLine(const std::string& message) { std::cerr << "mgrl: " << message << '\n'; }
/// Warnings: "mgrl: warning: MESSAGE".
inline void warnLine(const std::string& message) { std::cerr << "mgrl: warning: " << message << '\n'; }

}  // namespace mgrl::app::cli
