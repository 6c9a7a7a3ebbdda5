#pragma once
/// \file
/// Which scenario and which policy bundle a session opens (DESIGN.md sec. 5): the scenario
/// with every mistake that needs no graph found first, then the bundle: looked up, refused
/// from its manifest alone when it cannot serve, adopted with the settings it was trained
/// with when it names them, and its tables bound to the behaviours.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "mgrl/core/error.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/graph_source.hpp"
#include "mgrl/session/plugins.hpp"

namespace mgrl {

/// What every command, the viewer and the Python module give to open a scenario: the same
/// as the command line's SCENARIO, --data, --cache and --set.
struct SessionOptions {
  std::filesystem::path scenario;  ///< the scenario's YAML file
  std::filesystem::path dataDir;   ///< "": dataDirectory() (MGRL_DATA, ~/.local/share/mgrl, ../shared/mocap)
  std::filesystem::path cacheDir;  ///< "" MGRL_CACHE, else ~/.cache/mgrl
  std::vector<std::string> sets;   ///< --set KEY=VALUE, in order
  WarningSink log;                 ///< progress lines and messages (stderr); null: none
  /// The registries the behaviours are built from: mgrl::builtinPlugins() (app/builtins)
  /// for the built-in ones, or a caller's own. Required.
  const Plugins* plugins = nullptr;
};

/// " --set A --set B": the overrides in use, for hints that must reproduce them.
std::string setFlags(const std::vector<std::string>& sets);

/// The scenario with its behaviours checked: every mistake that needs no graph is found
/// before the graph is built or loaded.
Scenario checkedScenario(const SessionOptions& options);

/// Throws mgrl::Error ("--behavior: expected one of the scenario's behaviours (...), found
/// ...") unless `name` names one of `scenario`'s behaviours.
void requireBehavior(const Scenario& scenario, const std::string& name);

/// Where `mgrl train` puts a scenario's policy bundle by default:
/// <cache>/policies/<name>-<hash of the scenario's path, graph and behaviour settings>.
/// `graphKey`: the scenario's graphCacheKey() if the caller has it (else computed here).
std::filesystem::path defaultPolicyDirectory(const std::filesystem::path& cacheDir, const Scenario& scenario,
                                             const Plugins& plugins, std::string_view graphKey = {});

/// The refusals a policy bundle gets from its manifest alone (missing, another graph, a
/// behaviour missing or trained with other settings), made before the graph is loaded so
/// that the message is the only line on stderr. Throws mgrl::Error naming what to retrain.
/// `graphKey` as for defaultPolicyDirectory().
void precheckPolicy(const std::filesystem::path& dir, const Scenario& scenario, const SessionOptions& options,
                    std::string_view graphKey = {});

/// The policy bundle of eval and simulate, checked with precheckPolicy(): `policy`, else
/// the scenario's default bundle. An explicit `policy` made for the same graph whose
/// behaviours were trained with other settings (another learner, grid or budget) is used
/// with those settings: `scenario` is reloaded with them and the log says which. If
/// `graphKey` is given it receives the (final) scenario's graphCacheKey(), for the graph:
/// the key hashes every capture file, so a command computes it once.
std::filesystem::path resolvePolicy(const std::filesystem::path& policy, Scenario& scenario,
                                    const SessionOptions& options, std::string* graphKey = nullptr);

/// Loads the bundle into `bundle` and returns one part per behaviour (pointing into
/// `bundle` and `behaviors`), in order, leaving out the behaviour named `skip` (compare
/// supplies that one's table itself). Throws mgrl::Error for a missing or stale behaviour;
/// with `sameSettings` false (a sparring partner's bundle) a table trained with other
/// settings is taken when it fits the grid.
std::vector<PolicyPart> policyParts(const std::filesystem::path& dir, const std::vector<Behavior>& behaviors,
                                    const GraphResult& graph, const SessionOptions& options, PolicyBundle& bundle,
                                    const std::string& skip = {}, bool sameSettings = true);
/// The same for a bundle already loaded from `dir`.
std::vector<PolicyPart> policyPartsOf(PolicyBundle& bundle, const std::filesystem::path& dir,
                                      const std::vector<Behavior>& behaviors, const SessionOptions& options,
                                      const std::string& skip = {}, bool sameSettings = true);

}  // namespace mgrl
