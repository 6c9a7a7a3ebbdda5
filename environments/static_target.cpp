// static_target (Lee & Lee sec. 4.1): the target stays put in the world, so after an
// action it is seen from the action's end through the inverse of the action's root
// displacement: exact, no sampling.
#include <memory>

#include "environments.hpp"

namespace mgrl::environments {

void registerAll(EnvironmentRegistry& registry) {
  registry.add({"static_target",
                "the target stays put in the world; after an action it is seen from the action's end (exact)",
                {},
                [](const Params&) { return std::make_unique<StaticTarget>(); }});
}

}  // namespace mgrl::environments
