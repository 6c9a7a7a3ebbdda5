#pragma once
/// \file
/// The reward plugins (paper sec. 4.1, 6.4).
#include "mgrl/learning/reward.hpp"

namespace mgrl::rewards {

/// Adds approach and hit.
void registerAll(RewardRegistry& registry);

}  // namespace mgrl::rewards
