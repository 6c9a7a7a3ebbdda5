#pragma once
/// \file
/// The reward plugins (paper sec. 4.1, 6.4).
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/reward.hpp"
#include "term.hpp"

namespace mgrl::rewards {

/// Adds the reward terms with their success conditions, then approach, hit (the paper's, as
/// named presets) and terms (a list of `plugins.terms`).
void registerAll(BehaviorPlugins& plugins);

/// Adds approach and hit (rewards/rewards.cpp).
void registerPaperRewards(RewardRegistry& registry);
/// Adds terms (rewards/terms.cpp), a reward whose list names kinds of `terms`. `terms` must
/// outlive `registry` (both are members of one BehaviorPlugins); a kind added to it later
/// is found too.
void registerTerms(RewardRegistry& registry, const TermRegistry& terms);

}  // namespace mgrl::rewards
