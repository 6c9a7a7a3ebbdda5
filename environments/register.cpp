// The environment models this folder offers, in the order `mgrl list` shows them. A new
// model is its own file with its register function, declared in environments.hpp and named
// in the list below (docs/extending.md).
#include "environments.hpp"

namespace mgrl::environments {

void registerAll(EnvironmentRegistry& registry) {
  for (const auto add : {registerStaticTargets, registerOpponent, registerLearnedOpponent}) add(registry);
}

}  // namespace mgrl::environments
