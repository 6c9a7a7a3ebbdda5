#pragma once
/// \file
/// The EnvironmentModel seam (DESIGN.md sec. 4; paper sec. 4.1, 6.4): how the environment
/// state (the target, or an opponent, in the avatar frame of the decision) changes over one
/// graph action, and the two models every build has, `static_target` (the paper's) and
/// `moving_target`. The other models are plug-ins in environments/.
#include <cstddef>
#include <string>
#include <typeindex>
#include <typeinfo>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/random.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/environment_capabilities.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

/// The EnvironmentModel seam: the environment state in the avatar frame at the end of an
/// action, given the state at the decision, and how an evaluation trial's target starts.
/// What only some models can do (a target that stays put, targets that move, an opponent
/// that faces the avatar, a scripted fighter, a learned opponent and its self-play) is a
/// capability (environment_capabilities.hpp) asked for with as<C>().
class EnvironmentModel {
 public:
  virtual ~EnvironmentModel() = default;
  virtual std::string type() const = 0;
  virtual TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const = 0;
  /// The state of an evaluation trial's target placed at `position` (eval, compare): the
  /// position alone for a static target; a moving one draws its motion from `rng`.
  virtual TargetState draw(const Eigen::Vector3d& position, Rng&) const { return position; }
  /// Prepares the model for `model` before any next(); throws mgrl::Error.
  virtual void bind(const StateActionModel&) {}

  /// The capability C (environment_capabilities.hpp) this model offers, null if it does
  /// not: asked for once by the code that needs it (a task, a reward, trials), not per step.
  /// The pointer lives as long as the model.
  template <class C>
  const C* as() const {
    return static_cast<const C*>(capability(std::type_index(typeid(C))));
  }
  /// The same, to change it (SelfPlayOpponent::playPolicy()).
  template <class C>
  C* as() {
    // The capability is part of this model, which is not const here.
    return const_cast<C*>(std::as_const(*this).as<C>());
  }

 protected:
  /// What as<C>() returns for typeid(C): this model's C, null for one it does not offer
  /// (the default: none). An override names what it offers with offer().
  virtual const void* capability(std::type_index) const { return nullptr; }
  /// The one of `offered` whose type is `type`, else null:
  /// `return offer(type, static_cast<const FacingOpponent*>(this), &motion_);`.
  template <class... C>
  static const void* offer(std::type_index type, const C*... offered) {
    const void* found = nullptr;
    ((found = type == std::type_index(typeid(C)) ? static_cast<const void*>(offered) : found), ...);
    return found;
  }
};

/// `environment.next(model, action, e)` with e's stance held (TargetState::stance): what
/// trials and the online search step a stance-holding target with.
inline TargetState nextHoldingStance(const EnvironmentModel& environment, const StateActionModel& model,
                                     std::size_t action, const TargetState& e) {
  TargetState after = environment.next(model, action, e);
  after.stance = e.stance;
  return after;
}

using EnvironmentRegistry = Registry<EnvironmentModel>;

/// `static_target`: the target stays put in the world, so its new avatar-frame position is
/// the old one seen from the action's end, exactly (DESIGN.md sec. 3): the inverse of the
/// action's root displacement applied to e. Height is unchanged. A RigidTarget.
class StaticTarget final : public EnvironmentModel, public RigidTarget {
 public:
  std::string type() const override { return "static_target"; }
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;

 protected:
  const void* capability(std::type_index type) const override {
    return offer(type, static_cast<const RigidTarget*>(this));
  }
};

/// `moving_target`: the target moves on the ground at a constant speed for the episode, in
/// a straight line or, at a turn rate, round a circle (what TargetState::at() predicts);
/// after an action of T seconds it is at TargetState::at(T) seen from the action's end, its
/// heading turned by w T and back by the avatar's yaw. The speed and the turn rate are
/// kept bit for bit, so they can be a grid's layers. Offers its TargetMotion.
class MovingTarget final : public EnvironmentModel {
 public:
  /// `turnRates`: the turn rates an episode draws one of (rad/s, ascending); empty for
  /// straight lines only (what draw() did before turning targets, random stream included).
  MovingTarget(double minSpeed, double maxSpeed, std::vector<double> turnRates = {})
      : minSpeed_(minSpeed), motion_{maxSpeed, std::move(turnRates)} {}
  std::string type() const override { return "moving_target"; }
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;
  TargetState draw(const Eigen::Vector3d& position, Rng& rng) const override;

 protected:
  const void* capability(std::type_index type) const override { return offer(type, &motion_); }

 private:
  double minSpeed_;
  TargetMotion motion_;
};

/// The inverse of transformPoint(): a point of the frame `motion` starts from, seen from
/// the frame it leads to.
Eigen::Vector3d inverseTransformPoint(const GroundMotion& motion, const Eigen::Vector3d& point);

}  // namespace mgrl
