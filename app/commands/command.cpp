#include "command.hpp"

namespace mgrl::app::cli {

std::vector<std::unique_ptr<Command>> makeCommands(CLI::App& app, Common& common) {
  std::vector<std::unique_ptr<Command>> commands;
  for (auto* make : {inspectCommand, initCommand, graphCommand, trainCommand, evalCommand, simulateCommand,
                     compareCommand, serveCommand, statsCommand, listCommand})
    commands.push_back(make(app, common));
  return commands;
}

void fillSession(LearnOptions& options, const Common& common) {
  options.scenario = common.scenario;
  options.dataDir = common.dataDir;
  options.cacheDir = common.cacheDir;
  options.log = logLine;
}

}  // namespace mgrl::app::cli
