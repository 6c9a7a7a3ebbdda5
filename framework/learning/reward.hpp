#pragma once
/// \file
/// The Reward seam (DESIGN.md sec. 4; paper sec. 4.1, 6.4): the reward of taking an action
/// with the target at e (in the avatar frame of the decision), computed from the action's
/// samples in the StateActionModel, the in-action discount gamma^t included. gamma is the
/// reward's: the learner discounts what follows an action of t frames by gamma^t.
#include <cstddef>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"

namespace mgrl {

class Reward {
 public:
  virtual ~Reward() = default;
  virtual std::string type() const = 0;
  /// Discount per frame, in (0, 1].
  virtual double gamma() const = 0;
  /// r(e, a) >= 0.
  virtual double evaluate(const StateActionModel& model, std::size_t action, const Eigen::Vector3d& e) const = 0;
  /// Prepares the reward for `model` before any evaluate() with it: finds the joints its
  /// terms name (scenarios/README.md, body points). Throws ConfigError at the term's key
  /// (mgrl::Error without a YAML block) naming the roles and joints the skeleton has.
  virtual void bind(const StateActionModel&) {}
};

using RewardRegistry = Registry<Reward>;

/// The EnvironmentModel seam: where the target is, in the avatar frame at the end of an
/// action, given where it was at the decision.
class EnvironmentModel {
 public:
  virtual ~EnvironmentModel() = default;
  virtual std::string type() const = 0;
  virtual Eigen::Vector3d next(const StateActionModel& model, std::size_t action, const Eigen::Vector3d& e) const = 0;
  /// True if next() is exactly inverseTransformPoint(model.displacement(action), e), so
  /// learners may apply it from precomputed sines and cosines.
  virtual bool rigid() const { return false; }
};

using EnvironmentRegistry = Registry<EnvironmentModel>;

/// `static_target`: the target stays put in the world, so its new avatar-frame position is
/// the old one seen from the action's end, exactly (DESIGN.md sec. 3): the inverse of the
/// action's root displacement applied to e. Height is unchanged.
class StaticTarget final : public EnvironmentModel {
 public:
  std::string type() const override { return "static_target"; }
  Eigen::Vector3d next(const StateActionModel& model, std::size_t action, const Eigen::Vector3d& e) const override;
  bool rigid() const override { return true; }
};

/// The inverse of transformPoint(): a point of the frame `motion` starts from, seen from
/// the frame it leads to.
Eigen::Vector3d inverseTransformPoint(const GroundMotion& motion, const Eigen::Vector3d& point);

}  // namespace mgrl
