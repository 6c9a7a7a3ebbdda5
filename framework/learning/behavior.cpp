#include "mgrl/learning/behavior.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <tuple>

#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/real_bouts.hpp"

namespace mgrl {

namespace {

// The parameters of a plugin block, defaults filled in, as the registry reads them.
template <class Registry>
nlohmann::json blockJson(const Registry& registry, const ConfigNode& block, const std::string& fallbackType) {
  return registry.blockJson(block, fallbackType);
}

}  // namespace

std::pair<nlohmann::json, std::string> behaviorConfigAndKey(const BehaviorSpec& spec, const BehaviorPlugins& plugins,
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
  // Likewise a moving_target that does not turn (max_turn_deg_s: 0): turns has no
  // effect then, and neither key was there before.
  if (keyed["environment"].is_object() && keyed["environment"].contains("max_turn_deg_s") &&
      keyed["environment"]["max_turn_deg_s"].is_number() && keyed["environment"]["max_turn_deg_s"].get<double>() == 0) {
    keyed["environment"].erase("max_turn_deg_s");
    keyed["environment"].erase("turns");
  }
  // Likewise a learned opponent's against: previous, what self-play rounds did
  // before the choice.
  if (keyed["environment"].value("against", "") == "previous") keyed["environment"].erase("against");
  // Likewise effort's point: pelvis (the root's ground speed, all effort measured before).
  if (keyed["reward"].contains("terms") && keyed["reward"]["terms"].is_array()) {
    for (nlohmann::json& term : keyed["reward"]["terms"]) {
      if (term.value("term", "") == "effort" && term.value("point", "") == "pelvis") {
        term.erase("point");
      } else if (term.value("term", "") == "facing" && term.value("prefer", "") != "stance") {
        // And facing's stance and stances, which only prefer: stance reads.
        term.erase("stance");
        term.erase("stances");
      }
    }
  }
  Hasher h;
  h.update(std::string_view("mgrl.behavior.v1"));
  h.update(std::string_view(graphKey));
  h.update(std::string_view(keyed.dump()));
  // A facing term that learns from the real SNU bouts (prefer: bouts) reads capture beside
  // the scenario's: its samples go into the key, so a table learned from other bouts (another
  // data folder) is not taken for this one.
  const nlohmann::json& terms = keyed["reward"].contains("terms") ? keyed["reward"]["terms"] : nlohmann::json();
  if (terms.is_array() && std::any_of(terms.begin(), terms.end(), [](const nlohmann::json& term) {
        return term.value("term", "") == "facing" &&
               (term.value("prefer", "") == "bouts" || term.value("prefer", "") == "stance");
      })) {
    // (The term's bind has read them already, or failed at its `prefer` key.)
    const std::vector<double>& degrees = spec.reward.withLocation(
        []() -> const std::vector<double>& { return snuFacingDegrees(scenarioDataDirectory()); });
    h.update(std::string_view(reinterpret_cast<const char*>(degrees.data()), degrees.size() * sizeof(double)));
  }
  return {std::move(config), h.hex()};
}

namespace {

// An opponent's facing needs a grid axis to live on, and the avoid term and condition need
// an opponent to read strikes from: refuse either half alone, at the key that asks for it.
void checkOpponent(const BehaviorSpec& spec, const Behavior& b) {
  if (b.environment->as<FacingOpponent>()) {
    if (!b.discretizer->axis(AxisRole::Heading))
      spec.environment.child("type").fail(fmt::format(
          "expected a grid with a heading axis to hold the opponent's facing (polar_velocity with speeds: 1), found {}",
          b.discretizer->type()));
    return;
  }
  if (b.config["reward"].value("type", "") == "terms" && spec.reward.has("terms")) {
    const std::vector<ConfigNode> terms = spec.reward.child("terms").elements();
    for (std::size_t i = 0; i < terms.size(); ++i) {
      if (!terms[i].has("term")) continue;
      const std::string term = terms[i].child("term").asString();
      if (term == "avoid" || term == "struck")
        terms[i].child("term").fail(fmt::format(
            "expected environment: {{type: opponent}} or learned_opponent (the {} term reads the opponent's "
            "strikes), found {}",
            term, b.environment->type()));
    }
  }
  const std::string why =
      fmt::format("expected environment: {{type: opponent}} (the avoid term reads the opponent's strikes), found {}",
                  b.environment->type());
  if (b.success && b.success->clearance()) spec.success.fail(why);  // only a declared criterion has one
}

// A learned opponent: the model binds to the graph, the grid gets one layer per
// opponent state, the reward reads the opponent's track, and a policy bundle the scenario
// names is loaded for the opponent to play (its table for this behaviour, same grid).
void bindEnvironment(const BehaviorSpec& spec, Behavior& b, const StateActionModel& model,
                     const std::string& graphKey) {
  EnvironmentModel& environment = *b.environment;
  try {
    environment.bind(model);
  } catch (const ConfigError&) {
    throw;
  } catch (const Error& e) {
    spec.environment.child("type").fail(e.what());
  }
  if (const TrackedOpponent* opponent = environment.as<TrackedOpponent>()) {
    const std::size_t states = opponent->opponentStates();
    try {
      b.discretizer->setOpponentLayers(states);
    } catch (const Error& e) {
      spec.discretizer.child("type").fail(
          fmt::format("a learned opponent's {} states as grid layers: {}", states, e.what()));
    }
  }
  // A turn rate means something only beside the heading it turns (polar_velocity); on a grid
  // without one the values average over the turns as over the headings it cannot see.
  if (const TargetMotion* motion = environment.as<TargetMotion>();
      motion && !motion->turnRates.empty() && b.discretizer->axis(AxisRole::Heading)) {
    try {
      b.discretizer->setTurnLayers(motion->turnRates);
    } catch (const Error& e) {
      spec.discretizer.child("type").fail(fmt::format("a turning target's turn rates as grid layers: {}", e.what()));
    }
  }
  b.reward->bindEnvironment(&environment);
  SelfPlayOpponent* selfPlay = environment.as<SelfPlayOpponent>();
  const std::string source = selfPlay ? selfPlay->policySource() : std::string();
  if (source.empty()) return;
  const ConfigNode at = spec.environment.child("policy");
  try {
    PolicyBundle bundle = loadPolicyBundle(source, model, graphKey);
    auto found = bundle.behaviors.find(spec.name);
    if (found == bundle.behaviors.end())
      at.fail(fmt::format(
          "expected a table for behaviour {} in the policy bundle {}, found {}", spec.name, source,
          bundle.behaviors.empty() ? std::string("none") : [&] {
            std::string names;
            for (const auto& [name, _] : bundle.behaviors) names += (names.empty() ? "" : ", ") + name;
            return names;
          }()));
    auto table = std::make_shared<const QTable>(std::move(found->second.table));
    selfPlay->playPolicy(b.discretizer.get(), std::move(table), found->second.key);
  } catch (const ConfigError&) {
    throw;
  } catch (const Error& e) {
    at.fail(e.what());
  }
}

}  // namespace

int stanceCount(const std::vector<Behavior>& behaviors) {
  int count = 0;
  for (const Behavior& b : behaviors) count = std::max(count, b.stance + 1);
  return count;
}

Behavior buildBehavior(const BehaviorSpec& spec, const BehaviorPlugins& plugins, const StateActionModel& model,
                       const std::string& graphKey) {
  Behavior b;
  b.name = spec.name;
  b.weight = spec.weight;
  b.activation = spec.activation;
  b.stance = spec.stance;
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
  bindEnvironment(spec, b, model, graphKey);
  b.learner = plugins.learners.create(spec.learner);
  std::tie(b.config, b.key) = behaviorConfigAndKey(spec, plugins, graphKey);
  b.successDeclared = !spec.success.isNull();
  const nlohmann::json rewardTerms = b.reward->terms();
  b.success = b.successDeclared ? SuccessCriterion::read(spec.success, rewardTerms, plugins.conditions)
                                : SuccessCriterion::implied(rewardTerms, plugins.conditions);
  if (b.success) b.success->bind(model);
  checkOpponent(spec, b);
  return b;
}

}  // namespace mgrl
