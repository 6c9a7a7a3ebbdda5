#include "builtin_plugins.hpp"

#include "discretizers/discretizers.hpp"
#include "environments/environments.hpp"
#include "learners/learners.hpp"
#include "rewards/rewards.hpp"

namespace mgrl {

const Plugins& builtinPlugins() {
  static const Plugins instance = [] {
    Plugins p;
    discretizers::registerAll(p.discretizers);
    rewards::registerAll(p.rewards, p.conditions);
    environments::registerAll(p.environments);
    learners::registerAll(p.learners);
    return p;
  }();
  return instance;
}

}  // namespace mgrl
