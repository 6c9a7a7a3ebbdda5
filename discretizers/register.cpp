// The discretizers this folder offers, in the order `mgrl list` shows them. A new grid is
// its own file with its register function, declared in discretizers.hpp and named in the list
// below (docs/extending.md).
#include "discretizers.hpp"

namespace mgrl::discretizers {

void registerAll(DiscretizerRegistry& registry) {
  for (const auto add : {registerPolar2d, registerCylindrical3d, registerKdTree, registerPolarVelocity}) add(registry);
}

}  // namespace mgrl::discretizers
