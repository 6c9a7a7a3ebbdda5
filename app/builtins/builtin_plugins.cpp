#include "builtin_plugins.hpp"

#include <memory>

#include "discretizers/discretizers.hpp"
#include "environments/environments.hpp"
#include "learners/learners.hpp"
#include "mgrl/runtime/controller.hpp"
#include "rewards/rewards.hpp"

namespace mgrl {

namespace {

// The runtime's controllers (framework/runtime/controller.cpp), in the order `mgrl list`
// shows them and a wrong --controller's message names them.
void registerControllers(ControllerRegistry& controllers) {
  using Made = std::unique_ptr<Controller>;
  controllers.add({.name = "policy",
                   .summary = "the trained behaviours' weighted Q values, with the world's variety in simulate",
                   .needsPolicy = true,
                   .make = [](const ControllerChoice&, const ControllerParts& parts) -> Made {
                     return std::make_unique<PolicyController>(*parts.model, parts.policy, parts.variety);
                   }});
  controllers.add(
      {.name = "online_search",
       .summary = "depth-limited graph search for the best discounted reward (--horizon, --horizon-seconds)",
       .searches = true,
       .make = [](const ControllerChoice& choice, const ControllerParts& parts) -> Made {
         return std::make_unique<OnlineSearchController>(*parts.model, *parts.environment, parts.search,
                                                         SearchHorizon{choice.horizon, choice.horizonSeconds},
                                                         parts.gamma);
       }});
  controllers.add({.name = "random",
                   .summary = "a uniformly random out-action",
                   .make = [](const ControllerChoice&, const ControllerParts& parts) -> Made {
                     return std::make_unique<RandomController>(*parts.model);
                   }});
}

}  // namespace

void registerBuiltins(Plugins& plugins) {
  discretizers::registerAll(plugins.discretizers);
  rewards::registerAll(plugins);
  environments::registerAll(plugins.environments);
  learners::registerAll(plugins.learners);
  registerControllers(plugins.controllers);
}

const Plugins& builtinPlugins() {
  // Built in place: a Plugins is neither copied nor moved (its `terms` reward keeps the
  // address of its `terms` registry).
  struct Builtin : Plugins {
    Builtin() { registerBuiltins(*this); }
  };
  static const Builtin instance;
  return instance;
}

}  // namespace mgrl
