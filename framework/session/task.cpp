#include "mgrl/session/task.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "mgrl/learning/environment_model.hpp"

namespace mgrl {

double Task::targetHeight(double given) const {
  if (!std::isnan(given)) return given;
  if (world.targetHeight >= 0) return world.targetHeight;
  return std::numeric_limits<double>::quiet_NaN();
}

namespace {

// The first behaviour that does not share the first one's world, and what differs; null
// when they all agree.
struct Disagreement {
  const Behavior* behavior = nullptr;
  bool environment = false;  ///< else gamma
  std::string problem;
};

// A behaviour's environment block as built (defaults filled in); {} for a behaviour built
// by hand without a config (tests).
nlohmann::json environmentOf(const Behavior& b) {
  return b.config.is_object() ? b.config.value("environment", nlohmann::json::object()) : nlohmann::json::object();
}

Disagreement findDisagreement(const std::vector<Behavior>& behaviors) {
  const Behavior& first = behaviors.front();
  const nlohmann::json theirs = environmentOf(first);
  for (const Behavior& b : behaviors) {
    const nlohmann::json mine = environmentOf(b);
    if (mine != theirs)
      return {&b, true,
              fmt::format("expected the environment model of behaviors.{} ({}): a scenario's behaviours share one "
                          "world, found {}",
                          first.name, theirs.dump(), mine.dump())};
    if (b.reward->gamma() != first.reward->gamma())
      return {&b, false,
              fmt::format("expected gamma {:g} as behaviors.{}.reward has: a scenario's behaviours discount alike "
                          "(the online search and eval's returns use one gamma), found {:g}",
                          first.reward->gamma(), first.name, b.reward->gamma())};
  }
  return {};
}

Task taskOf(const Behavior& first) {
  Task task;
  const EnvironmentModel& environment = *first.environment;
  task.environment = &environment;
  task.gamma = first.reward->gamma();
  task.opponent = environment.as<FacingOpponent>() != nullptr;
  task.targetMotion = environment.as<TargetMotion>();
  task.trackedOpponent = environment.as<TrackedOpponent>();
  task.opponentPhases = task.trackedOpponent ? task.trackedOpponent->opponentPhases() : 0;
  task.scriptedOpponent = environment.as<ScriptedOpponent>();
  return task;
}

}  // namespace

Task makeTask(const std::vector<Behavior>& behaviors, const std::string& source) {
  if (behaviors.empty()) throw Error(fmt::format("{}: expected at least one behaviour, found none", source));
  const Disagreement d = findDisagreement(behaviors);
  if (d.behavior)
    throw Error(fmt::format("{}: behaviors.{}.{}: {}", source, d.behavior->name,
                            d.environment ? "environment" : "reward.gamma", d.problem));
  return taskOf(behaviors.front());
}

Task makeTask(const Scenario& scenario, const std::vector<Behavior>& behaviors) {
  if (behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour (see scenarios/README.md), "
                       "found none");
  // Every behaviour of a scenario acts in the one world: the target moves one way, and
  // returns are discounted alike (the online search and eval's returns use this gamma).
  const Disagreement d = findDisagreement(behaviors);
  if (d.behavior) {
    for (const BehaviorSpec& spec : scenario.behaviors) {
      if (spec.name != d.behavior->name) continue;
      if (d.environment) {
        if (spec.environment.has("type")) spec.environment.fail(d.problem);
        spec.node.fail(fmt::format("environment: {}", d.problem));
      }
      if (spec.reward.has("gamma")) spec.reward.child("gamma").fail(d.problem);
      spec.reward.fail(fmt::format("gamma: {}", d.problem));
    }
    makeTask(behaviors, scenario.path.string());  // throws: no block to point at
  }
  Task task = taskOf(behaviors.front());
  task.world = readWorldParams(scenario.root.has("world") ? scenario.root.child("world")
                                                          : ConfigNode::parse("", "world"));
  return task;
}

}  // namespace mgrl
