#pragma once
// Shared by `mgrl train` and `mgrl eval` (app/train_command.cpp, app/eval_command.cpp).
#include <chrono>
#include <string>
#include <string_view>
#include <vector>

#include "graph_command.hpp"
#include "learn_commands.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/scenario/scenario.hpp"

namespace mgrl::app {

using Clock = std::chrono::steady_clock;

/// "4.17 M", "850.0 k": counts and rates for people (with a trailing space for units).
std::string humanCount(double n);

/// "88.3 MB", "47.40 GB".
std::string humanBytes(double bytes);

/// A duration for people: "12.31 s", "4.2 ms", "0.3 ms" (never "0.00 s").
std::string humanSeconds(double seconds);

/// " --set A --set B": the overrides in use, for hints that must reproduce them.
std::string setFlags(const std::vector<std::string>& sets);

/// The scenario with its behaviours checked: every mistake that needs no graph is found
/// before the graph is built or loaded.
Scenario checkedScenario(const LearnOptions& options);

/// Seconds since the program started (its static initialisation): eval and simulate
/// report it at their first decision as "startup_seconds" (issue 20: <= 0.05 s with a
/// cached graph).
double secondsSinceStart();

struct Loaded {
  Scenario scenario;
  GraphResult graph;
};

/// Throws mgrl::Error ("--behavior: expected one of the scenario's behaviours (...), found
/// ...") unless `name` names one of `scenario`'s behaviours.
void requireBehavior(const Scenario& scenario, const std::string& name);

/// The scenario's graph, from the cache or built (options.log hears about it). `motion`:
/// parse the capture even if the graph is cached (GraphOptions::motion); without it
/// Loaded::graph.db may be empty.
/// `graphKey`: the scenario's graphCacheKey() if the caller has it (resolvePolicy()).
Loaded load(const LearnOptions& options, Scenario scenario, bool motion = true, std::string graphKey = {});

/// The refusals a policy bundle gets from its manifest alone (missing, another graph, a
/// behaviour missing or trained with other settings), made before the graph is loaded so
/// that the message is the only line on stderr. Throws mgrl::Error naming what to retrain.
/// `graphKey` as for defaultPolicyDirectory().
void precheckPolicy(const std::filesystem::path& dir, const Scenario& scenario, const LearnOptions& options,
                    std::string_view graphKey = {});

/// The policy bundle of eval and simulate, checked with precheckPolicy(): `policy`, else
/// the scenario's default bundle. An explicit `policy` made for the same graph whose
/// behaviours were trained with other settings (another learner, grid or budget) is used
/// with those settings: `scenario` is reloaded with them and the log says which. If
/// `graphKey` is given it receives the (final) scenario's graphCacheKey(), for load(): the
/// key hashes every capture file, so a command computes it once.
std::filesystem::path resolvePolicy(const std::filesystem::path& policy, Scenario& scenario,
                                    const LearnOptions& options, std::string* graphKey = nullptr);

/// Loads the bundle into `bundle` and returns one part per behaviour (pointing into
/// `bundle` and `behaviors`), in order, leaving out the behaviour named `skip` (compare
/// supplies that one's table itself). Throws mgrl::Error for a missing or stale behaviour.
std::vector<PolicyPart> policyParts(const std::filesystem::path& dir, const std::vector<Behavior>& behaviors,
                                    const GraphResult& graph, const LearnOptions& options, PolicyBundle& bundle,
                                    const std::string& skip = {});

}  // namespace mgrl::app
