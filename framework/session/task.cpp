#include "mgrl/session/task.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "mgrl/learning/reward.hpp"

namespace mgrl {

double Task::targetHeight(double given) const {
  if (!std::isnan(given)) return given;
  if (world.targetHeight >= 0) return world.targetHeight;
  return std::numeric_limits<double>::quiet_NaN();
}

Task makeTask(const Scenario& scenario, const std::vector<Behavior>& behaviors) {
  if (behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour (see scenarios/README.md), "
                       "found none");
  const Behavior& first = behaviors.front();
  // Every behaviour of a scenario acts in the one world: the target moves one way, and
  // returns are discounted alike (the online search and eval's returns use this gamma).
  auto specOf = [&](const Behavior& b) -> const BehaviorSpec* {
    for (const BehaviorSpec& spec : scenario.behaviors)
      if (spec.name == b.name) return &spec;
    return nullptr;
  };
  for (const Behavior& b : behaviors) {
    const BehaviorSpec* spec = specOf(b);
    const nlohmann::json& mine = b.config.value("environment", nlohmann::json::object());
    const nlohmann::json& theirs = first.config.value("environment", nlohmann::json::object());
    if (mine != theirs) {
      const std::string problem =
          fmt::format("expected the environment model of behaviors.{} ({}): a scenario's behaviours share one world, "
                      "found {}",
                      first.name, theirs.dump(), mine.dump());
      if (spec && spec->environment.has("type")) spec->environment.fail(problem);
      if (spec) spec->node.fail(fmt::format("environment: {}", problem));
      throw Error(fmt::format("{}: behaviors.{}.environment: {}", scenario.path.string(), b.name, problem));
    }
    if (b.reward->gamma() != first.reward->gamma()) {
      const std::string problem =
          fmt::format("expected gamma {:g} as behaviors.{}.reward has: a scenario's behaviours discount alike (the "
                      "online search and eval's returns use one gamma), found {:g}",
                      first.reward->gamma(), first.name, b.reward->gamma());
      if (spec && spec->reward.has("gamma")) spec->reward.child("gamma").fail(problem);
      if (spec) spec->reward.fail(fmt::format("gamma: {}", problem));
      throw Error(fmt::format("{}: behaviors.{}.reward.gamma: {}", scenario.path.string(), b.name, problem));
    }
  }
  Task task;
  task.environment = first.environment.get();
  task.gamma = first.reward->gamma();
  task.opponent = first.environment->faces();
  task.world = readWorldParams(scenario.root.has("world") ? scenario.root.child("world")
                                                          : ConfigNode::parse("", "world"));
  return task;
}

}  // namespace mgrl
