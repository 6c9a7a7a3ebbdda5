// The learners this folder offers, in the order `mgrl list` shows them. A new learner is
// its own file with its register function, declared in learners.hpp and named in the list
// below (docs/extending.md).
#include "learners.hpp"

namespace mgrl::learners {

void registerAll(LearnerRegistry& registry) {
  for (const auto add :
       {registerQLearning, registerValueIteration, registerAdaptiveValueIteration, registerMpiValueIteration})
    add(registry);
}

}  // namespace mgrl::learners
