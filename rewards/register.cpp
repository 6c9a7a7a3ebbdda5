// The rewards this folder offers, and the terms of the `terms` reward, in the order
// `mgrl list` shows them. A new reward or term is its own file with its register function,
// declared in rewards.hpp (a term: term.hpp) and called here.
#include "rewards.hpp"

namespace mgrl::rewards {

void registerAll(RewardRegistry& registry) {
  registerPaperRewards(registry);
  registerTerms(registry);
}

const TermRegistry& termRegistry() {
  static const TermRegistry registry = [] {
    TermRegistry terms("reward term");
    registerDistance(terms);
    registerFacing(terms);
    registerContact(terms);
    registerTravel(terms);
    registerEffort(terms);
    registerAvoid(terms);
    return terms;
  }();
  return registry;
}

}  // namespace mgrl::rewards
