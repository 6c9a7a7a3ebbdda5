#pragma once
/// \file
/// The Reward seam (DESIGN.md sec. 4; paper sec. 4.1, 6.4): the reward of taking an action
/// in the environment state e (the target in the avatar frame of the decision; a moving
/// target is at e.at(t) t seconds into the action), computed from the action's
/// samples in the StateActionModel, the in-action discount gamma^t included. gamma is the
/// reward's: the learner discounts what follows an action of t frames by gamma^t.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

class EnvironmentModel;

class Reward {
 public:
  virtual ~Reward() = default;
  virtual std::string type() const = 0;
  /// Discount per frame, in (0, 1].
  virtual double gamma() const = 0;
  /// r(e, a) >= 0.
  virtual double evaluate(const StateActionModel& model, std::size_t action, const TargetState& e) const = 0;
  /// Prepares the reward for `model` before any evaluate() with it: finds the joints its
  /// terms name (scenarios/README.md, body points). Throws ConfigError at the term's key
  /// (mgrl::Error without a YAML block) naming the roles and joints the skeleton has.
  virtual void bind(const StateActionModel&) {}
  /// The behaviour's environment model (it outlives the reward), before any evaluate(): a
  /// reward whose terms read a learned opponent's actual body and strikes asks it for its
  /// TrackedOpponent, once, and then for them (TrackedOpponent::track).
  virtual void bindEnvironment(const EnvironmentModel*) {}
  /// The reward as reward terms, a JSON list of {"term": NAME, parameters...}: a success
  /// condition takes what it leaves out from the reward's term of its kind (success.hpp).
  /// A preset lists what it amounts to; a reward with no such terms, an empty list.
  virtual nlohmann::json terms() const { return nlohmann::json::array(); }
};

using RewardRegistry = Registry<Reward>;

}  // namespace mgrl
