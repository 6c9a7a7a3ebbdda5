// The rewards this folder offers, in the order `mgrl list` shows them. A new reward is its
// own file with its register function, declared and called here.
#include "rewards.hpp"

namespace mgrl::rewards {

void registerAll(RewardRegistry& registry) {
  registerPaperRewards(registry);
  registerTerms(registry);
}

}  // namespace mgrl::rewards
