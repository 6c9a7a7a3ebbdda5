#pragma once
/// \file
/// The environment-model plugins (DESIGN.md sec. 4): how the target moves relative to the
/// avatar under an action.
#include "mgrl/learning/reward.hpp"

namespace mgrl::environments {

/// Adds static_target (the paper's: the target stays put in the world).
void registerAll(EnvironmentRegistry& registry);

}  // namespace mgrl::environments
