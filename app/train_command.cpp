// `mgrl train` (DESIGN.md sec. 5): trains a scenario's behaviours and saves a policy bundle,
// through the session stage's training (mgrl/session/training.hpp).
#include <fmt/format.h>

#include "learn_commands.hpp"
#include "mgrl/core/launch.hpp"
#include "mgrl/core/numbers.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/session.hpp"
#include "train_support.hpp"

namespace mgrl::app {

using json = nlohmann::json;

json runTrain(const TrainOptions& given) {
  // Under an MPI launcher only rank 0 speaks (trainScenario keeps the others silent too).
  TrainOptions options = given;
  if (launchedProcess().rank != 0) options.log = nullptr;
  // The scenario, its graph and behaviours, and the task they share (behaviours that do not
  // share one world are refused here, not after training); the model is enough: no poses.
  // The bundle's folder is checked before the graph is built, and long before training.
  SessionNeeds needs;
  needs.motion = false;
  needs.beforeGraph = [&](const Scenario& scenario) {
    if (!options.behavior.empty()) requireBehavior(scenario, options.behavior);
    bundleFolder(options, options, scenario);
  };
  const std::unique_ptr<const Session> session = openSession(options, needs);
  TrainHooks hooks;
  hooks.log = options.log;
  hooks.progressBar = options.progressBar;
  hooks.listen = options.listen;
  hooks.stop = &stopRequested;
  const StopSignals signals;  // Ctrl-C and SIGTERM raise stopRequested
  return trainScenario(*session, options, hooks).report;
}

std::string trainText(const json& report) {
  std::string text = fmt::format("policy bundle: {}\n", report["policy"].get<std::string>());
  for (const auto& [name, b] : report["behaviors"].items())
    text += fmt::format("  {:<10} {:<16} {:>12} updates  {:8.2f} s  {:>9}updates/s  residual {:.3g}  table {:.1f} MB\n",
                        name, b["learner"].get<std::string>(), b["updates"].get<std::uint64_t>(),
                        b["seconds"].get<double>(), humanCount(b["updates_per_second"].get<double>()),
                        b["final_residual"].get<double>(), b["table_bytes"].get<double>() / 1e6);
  if (report.contains("kept"))
    for (const json& name : report["kept"])
      text += fmt::format("  {:<10} kept: trained before the run was stopped\n", name.get<std::string>());
  return text;
}

}  // namespace mgrl::app
