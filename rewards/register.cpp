// The rewards this folder offers, and the terms of the `terms` reward, in the order
// `mgrl list` shows them. A new reward or term is its own file with its register function,
// declared in rewards.hpp (a term: term.hpp) and called (a term: named in the list) here.
#include "rewards.hpp"

namespace mgrl::rewards {

void registerAll(BehaviorPlugins& plugins) {
  Vocabulary vocabulary{plugins.terms, plugins.conditions};
  for (const auto add : {registerDistance, registerFacing, registerContact, registerTravel, registerEffort,
                         registerAvoid, registerStruck, registerReversal})
    add(vocabulary);
  registerPaperRewards(plugins.rewards);
  registerTerms(plugins.rewards, plugins.terms);
}

}  // namespace mgrl::rewards
