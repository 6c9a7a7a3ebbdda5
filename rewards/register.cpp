// The rewards this folder offers, and the terms of the `terms` reward, in the order
// `mgrl list` shows them. A new reward or term is its own file with its register function,
// declared in rewards.hpp (a term: term.hpp) and called (a term: named in the list) here.
#include "rewards.hpp"

namespace mgrl::rewards {

void registerAll(RewardRegistry& registry, ConditionRegistry& conditions) {
  registerPaperRewards(registry);
  registerTerms(registry);
  for (const ConditionRegistry::Entry& kind : conditionRegistry().entries()) conditions.add(kind);
}

namespace {

const Vocabulary& vocabulary() {
  static const Vocabulary v = [] {
    Vocabulary terms;
    for (const auto add : {registerDistance, registerFacing, registerContact, registerTravel, registerEffort,
                           registerAvoid, registerStruck})
      add(terms);
    return terms;
  }();
  return v;
}

}  // namespace

const TermRegistry& termRegistry() { return vocabulary().terms; }
const ConditionRegistry& conditionRegistry() { return vocabulary().conditions; }

}  // namespace mgrl::rewards
