#include "mgrl/scenario/behaviors.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace mgrl {

void checkBehaviors(const Scenario& scenario, const BehaviorPlugins& plugins) {
  for (const BehaviorSpec& spec : scenario.behaviors) {
    plugins.discretizers.check(spec.discretizer);
    plugins.rewards.check(spec.reward);
    if (!spec.environment.isNull()) plugins.environments.check(spec.environment);
    plugins.learners.check(spec.learner);
    if (!spec.success.isNull())
      SuccessCriterion::read(spec.success, plugins.rewards.create(spec.reward)->terms(), plugins.conditions);
  }
}

std::vector<Behavior> buildBehaviors(const Scenario& scenario, const BehaviorPlugins& plugins,
                                     const StateActionModel& model, const std::string& graphKey,
                                     const std::string& only) {
  if (scenario.behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour to train, found none");
  std::vector<std::string> names;
  for (const BehaviorSpec& spec : scenario.behaviors) names.push_back(spec.name);
  if (!only.empty() && std::find(names.begin(), names.end(), only) == names.end())
    throw Error(fmt::format("--behavior: expected one of the scenario's behaviours ({}), found {}",
                            fmt::join(names, ", "), quoteToken(only)));
  std::vector<Behavior> result;
  for (const BehaviorSpec& spec : scenario.behaviors)
    if (only.empty() || spec.name == only) result.push_back(buildBehavior(spec, plugins, model, graphKey));
  return result;
}

}  // namespace mgrl
