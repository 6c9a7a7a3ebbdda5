#pragma once
// Shared by `mgrl train` and `mgrl eval` (app/train_command.cpp, app/eval_command.cpp).
#include <chrono>
#include <string>
#include <string_view>
#include <vector>

#include "graph_command.hpp"
#include "learn_commands.hpp"
#include "mgrl/core/numbers.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/policy_source.hpp"

namespace mgrl::app {

// Moved to the session stage (framework/include/mgrl/session/policy_source.hpp).
using mgrl::checkedScenario;
using mgrl::policyParts;
using mgrl::precheckPolicy;
using mgrl::requireBehavior;
using mgrl::resolvePolicy;
using mgrl::setFlags;

using Clock = std::chrono::steady_clock;

/// Seconds since the program started (its static initialisation): eval and simulate
/// report it at their first decision as "startup_seconds" (issue 20: <= 0.05 s with a
/// cached graph).
double secondsSinceStart();

struct Loaded {
  Scenario scenario;
  GraphResult graph;
};


/// The scenario's graph, from the cache or built (options.log hears about it). `motion`:
/// parse the capture even if the graph is cached (GraphOptions::motion); without it
/// Loaded::graph.db may be empty.
/// `graphKey`: the scenario's graphCacheKey() if the caller has it (resolvePolicy()).
Loaded load(const LearnOptions& options, Scenario scenario, bool motion = true, std::string graphKey = {});

}  // namespace mgrl::app
