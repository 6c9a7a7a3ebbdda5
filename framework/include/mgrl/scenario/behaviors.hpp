#pragma once
/// \file
/// A scenario's behaviours built through the registries (mgrl/learning/behavior.hpp for
/// one behaviour): checked before a graph is needed, then built on the graph's model.
#include <string>
#include <vector>

#include "mgrl/learning/behavior.hpp"
#include "mgrl/scenario/scenario.hpp"

namespace mgrl {

/// Checks every behaviour's plugin types and parameters (all that can be checked without
/// the graph), so that a typo is reported before a graph is built or loaded.
void checkBehaviors(const Scenario& scenario, const BehaviorPlugins& plugins);

/// Builds every behaviour of the scenario, or only `only` (an unknown name is an error
/// listing the scenario's behaviours). A scenario without behaviours is an error.
std::vector<Behavior> buildBehaviors(const Scenario& scenario, const BehaviorPlugins& plugins,
                                     const StateActionModel& model, const std::string& graphKey,
                                     const std::string& only = "");

}  // namespace mgrl
