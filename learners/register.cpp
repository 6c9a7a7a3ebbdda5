// The learners this folder offers, in the order `mgrl list` shows them. A new learner is
// its own file with its register function, declared and called here (docs/extending.md).
#include "learners.hpp"

namespace mgrl::learners {

void registerAll(LearnerRegistry& registry) {
  for (const auto add :
       {registerQLearning, registerValueIteration, registerAdaptiveValueIteration, registerMpiValueIteration})
    add(registry);
}

}  // namespace mgrl::learners
