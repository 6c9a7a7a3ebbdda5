#pragma once
/// \file
/// The reward plugins (paper sec. 4.1, 6.4) and the built-in environment model.
#include "mgrl/reward.hpp"

namespace mgrl::rewards {

/// Adds approach and hit.
void registerAll(RewardRegistry& registry);

/// Adds static_target (the paper's: the target stays put in the world).
void registerEnvironments(EnvironmentRegistry& registry);

}  // namespace mgrl::rewards
