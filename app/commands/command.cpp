#include "command.hpp"

#include "command_line.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl::app::cli {

std::vector<std::unique_ptr<Command>> makeCommands(CLI::App& app, Common& common) {
  std::vector<std::unique_ptr<Command>> commands;
  for (auto* make : {inspectCommand, initCommand, graphCommand, trainCommand, evalCommand, simulateCommand,
                     compareCommand, serveCommand, statsCommand, listCommand})
    commands.push_back(make(app, common));
  return commands;
}

void fillSession(SessionOptions& options, const Common& common) {
  options.scenario = common.scenario;
  options.dataDir = common.dataDir;
  options.cacheDir = common.cacheDir;
  options.log = logLine;
}

SessionCommand::SessionCommand(CLI::App* sub, Common& common, const std::string& scenarioHelp) : Command(sub) {
  sub_->add_option("SCENARIO", common.scenario, scenarioHelp)->required();
}

void SessionCommand::addSessionOptions(SessionOptions& options, Common& common, bool json, const std::string& setHelp) {
  session_ = &options;
  sub_->add_option("--set", options.sets, setHelp);
  if (json) sub_->add_flag("--json", common.json, "Print one JSON object on stdout");
  addDataAndCache(sub_, common.dataDir, common.cacheDir);
}

void SessionCommand::run(const Common& common) {
  if (session_ == nullptr) throw Error("internal: a session command without its session options");
  fillSession(*session_, common);
  runSession(common);
}

}  // namespace mgrl::app::cli
