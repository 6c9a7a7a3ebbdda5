#include "mgrl/learning/behavior.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <tuple>

#include "mgrl/core/hash.hpp"

namespace mgrl {

namespace {

// The parameters of a plugin block, defaults filled in, as the registry reads them.
template <class Registry>
nlohmann::json blockJson(const Registry& registry, const ConfigNode& block, const std::string& fallbackType) {
  return registry.blockJson(block, fallbackType);
}

}  // namespace

std::pair<nlohmann::json, std::string> behaviorConfigAndKey(const BehaviorSpec& spec, const Plugins& plugins,
                                                             const std::string& graphKey) {
  nlohmann::json config = {{"discretizer", blockJson(plugins.discretizers, spec.discretizer, "")},
                           {"reward", blockJson(plugins.rewards, spec.reward, "")},
                           {"environment", blockJson(plugins.environments, spec.environment, "static_target")},
                           {"learner", blockJson(plugins.learners, spec.learner, "")}};
  nlohmann::json keyed = config;
  for (const char* irrelevant : {"threads", "curve_points", "curve_sample", "checkpoint_every"}) keyed["learner"].erase(irrelevant);
  // A parameter added after tables were trained keeps their keys while it holds the value
  // that reproduces them bit for bit (q_learning's max_episode_actions: 0, the paper's rule).
  if (keyed["learner"].value("max_episode_actions", std::int64_t{0}) == 0) keyed["learner"].erase("max_episode_actions");
  // Likewise effort's point: pelvis (the root's ground speed, all effort measured before).
  if (keyed["reward"].contains("terms") && keyed["reward"]["terms"].is_array())
    for (nlohmann::json& term : keyed["reward"]["terms"])
      if (term.value("term", "") == "effort" && term.value("point", "") == "pelvis") term.erase("point");
  Hasher h;
  h.update(std::string_view("mgrl.behavior.v1"));
  h.update(std::string_view(graphKey));
  h.update(std::string_view(keyed.dump()));
  return {std::move(config), h.hex()};
}

Behavior buildBehavior(const BehaviorSpec& spec, const Plugins& plugins, const StateActionModel& model,
                       const std::string& graphKey) {
  Behavior b;
  b.name = spec.name;
  b.weight = spec.weight;
  b.activation = spec.activation;
  b.discretizer = plugins.discretizers.create(spec.discretizer, model);
  b.reward = plugins.rewards.create(spec.reward);
  b.reward->bind(model);
  if (spec.environment.isNull()) {
    const auto* entry = plugins.environments.find("static_target");
    if (!entry) throw Error("no environment model 'static_target' registered");
    b.environment = entry->make(Params::defaults(entry->params));
  } else {
    b.environment = plugins.environments.create(spec.environment);
  }
  b.learner = plugins.learners.create(spec.learner);
  std::tie(b.config, b.key) = behaviorConfigAndKey(spec, plugins, graphKey);
  b.successDeclared = !spec.success.isNull();
  b.success = b.successDeclared ? SuccessCriterion::read(spec.success, b.config["reward"])
                                : SuccessCriterion::implied(b.config["reward"]);
  if (b.success) b.success->bind(model);
  return b;
}

}  // namespace mgrl
