#pragma once
/// \file
/// Behaviours (DESIGN.md sec. 2, "learn"): a scenario's `behaviors:` entry turned into
/// plugin instances through the registries, and the key that says which trained table
/// belongs to it.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/learning/behavior_spec.hpp"
#include "mgrl/learning/discretizer.hpp"
#include "mgrl/learning/environment_model.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/reward.hpp"
#include "mgrl/learning/reward_term.hpp"
#include "mgrl/learning/success.hpp"

namespace mgrl {

/// One registry per seam a behaviour is built from; the composition root fills them
/// (app/builtins: the built-in plug-ins) and hands them to the session stage as part of its
/// Plugins (mgrl/session/plugins.hpp, which adds the controllers).
///
/// Neither copied nor moved: a reward that reads the other registries (the `terms` reward
/// reads `terms`) keeps the address of the object it was registered in.
struct BehaviorPlugins {
  BehaviorPlugins() = default;
  BehaviorPlugins(const BehaviorPlugins&) = delete;
  BehaviorPlugins& operator=(const BehaviorPlugins&) = delete;

  DiscretizerRegistry discretizers{"discretizer"};
  RewardRegistry rewards{"reward"};
  TermRegistry terms{"reward term"};  ///< the terms of the `terms` reward
  EnvironmentRegistry environments{"environment model"};
  LearnerRegistry learners{"learner"};
  ConditionRegistry conditions{"success term"};  ///< registered beside the reward terms of the same name
};

struct Behavior {
  std::string name;
  double weight = 1;
  Activation activation = Activation::Always;
  int stance = -1;  ///< BehaviorSpec::stance
  std::unique_ptr<Discretizer> discretizer;
  std::unique_ptr<Reward> reward;
  std::unique_ptr<EnvironmentModel> environment;
  std::unique_ptr<Learner> learner;
  /// {"discretizer": {"type", params...}, "reward": ..., "environment": ..., "learner": ...}
  /// with every parameter, defaults included.
  nlohmann::json config;
  /// Hash of the graph key and everything in `config` that changes the trained table (not
  /// weight or activation, not threads, curve_points or checkpoint_every).
  std::string key;
  /// What success means for it (`success:`, else implied by its reward's contact term;
  /// none for a reward without one). Not part of the key: it does not change the table.
  std::optional<SuccessCriterion> success;
  bool successDeclared = false;  ///< `success:` was given

  Problem problem(const StateActionModel& model) const { return {model, *discretizer, *reward, *environment}; }
};

/// A behaviour's `config` and `key` (see Behavior) without building its plugins: enough to
/// tell whether a trained table belongs to it. Throws ConfigError like buildBehavior().
std::pair<nlohmann::json, std::string> behaviorConfigAndKey(const BehaviorSpec& spec, const BehaviorPlugins& plugins,
                                                            const std::string& graphKey);

/// The stances the behaviours number: the largest `stance` plus one, 0 for none
/// (the scenario reader has checked that 0..N-1 each have a behaviour).
int stanceCount(const std::vector<Behavior>& behaviors);

/// Builds a behaviour's plugins; ConfigError (`file:line:col: behaviors.NAME.reward.type:
/// unknown reward 'x' (known: approach, hit)`) for unknown types and bad parameters.
Behavior buildBehavior(const BehaviorSpec& spec, const BehaviorPlugins& plugins, const StateActionModel& model,
                       const std::string& graphKey);

}  // namespace mgrl
