#pragma once
/// \file
/// The reward plugins (paper sec. 4.1, 6.4).
#include <string>
#include <string_view>
#include <vector>

#include "mgrl/learning/reward.hpp"
#include "term.hpp"

namespace mgrl::rewards {

/// Adds approach, hit (the paper's, as named presets) and terms (the vocabulary), and the
/// terms' success conditions.
void registerAll(RewardRegistry& registry, ConditionRegistry& conditions);

/// Adds approach and hit (rewards/rewards.cpp).
void registerPaperRewards(RewardRegistry& registry);
/// Adds terms (rewards/terms.cpp).
void registerTerms(RewardRegistry& registry);

/// Text for `mgrl list`: every term of the vocabulary with its parameters (term.hpp).
std::string describeTerms(std::string_view indent);

}  // namespace mgrl::rewards
