// The mgrl command line (DESIGN.md sec. 5). Errors: one line on stderr, non-zero exit;
// --json: one JSON object on stdout and nothing else there. The commands themselves are in
// app/commands/, one object each.

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "command_line.hpp"
#include "commands/command.hpp"
#include "learn_commands.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/version.hpp"

using namespace mgrl::app::cli;  // NOLINT: the command line's own helpers (command_line.hpp)

namespace {

constexpr int kExitError = 1;
constexpr int kExitUsage = 2;
constexpr int kExitInterrupted = 130;  // as a shell reports a Ctrl-C

}  // namespace

int main(int argc, char** argv) {
  Common common;
  // `mgrl stats --compare REAL... -- SYNTH...`: what follows `--` is the second group.
  // CLI11 would fold it into the positionals, so it is cut off before parsing.
  if (argc > 1 && std::string(argv[1]) == "stats")
    for (int i = 2; i < argc; ++i)
      if (std::string(argv[i]) == "--") {
        common.afterDash.assign(argv + i + 1, argv + argc);
        common.dash = true;
        argc = i;
        break;
      }
  CLI::App app{"mgrl: train avatar behaviours from unlabelled motion capture with reinforcement learning on a "
               "motion graph (after Lee & Lee, SCA 2004)."};
  app.set_version_flag("--version", std::string("mgrl ") + mgrl::kVersion);
  app.require_subcommand(1);
  const std::vector<std::unique_ptr<Command>> commands = makeCommands(app, common);

  // CLI11 would call an unknown command a missing one; name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    std::vector<std::string> known;
    for (const CLI::App* command : app.get_subcommands({})) known.push_back(command->get_name());
    if (std::find(known.begin(), known.end(), argv[1]) == known.end()) {
      std::cerr << fmt::format("mgrl: expected a command ({}), found '{}' (see mgrl --help)\n", fmt::join(known, ", "),
                               argv[1]);
      return kExitUsage;
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 says only "arguments were not expected": name the option and the nearest one.
    if (argc > 1) {
      const std::vector<std::string> args(argv + 2, argv + argc);
      for (const CLI::App* command : app.get_subcommands({}))
        if (command->get_name() == argv[1]) {
          const std::string unknown = unknownOption(*command, args);
          if (!unknown.empty()) {
            std::cerr << "mgrl: " << unknown << '\n';
            return kExitUsage;
          }
        }
    }
    std::cerr << "mgrl: " << e.what() << " (see mgrl --help)\n";
    return kExitUsage;
  }

  try {
    for (const auto& command : commands)
      if (command->parsed()) command->run(common);
  } catch (const mgrl::Interrupted& e) {
    std::cerr << "mgrl: " << e.what() << '\n';
    return kExitInterrupted;
  } catch (const mgrl::Error& e) {
    std::cerr << "mgrl: " << e.what() << '\n';
    return kExitError;
  } catch (const std::exception& e) {
    std::cerr << "mgrl: internal error: " << e.what() << '\n';
    return kExitError;
  }
  return 0;
}
