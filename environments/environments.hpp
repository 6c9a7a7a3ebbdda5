#pragma once
/// \file
/// The environment-model plugins (DESIGN.md sec. 4): how the target moves relative to the
/// avatar under an action.
#include "mgrl/learning/reward.hpp"

namespace mgrl::environments {

/// Adds static_target (the paper's: the target stays put in the world), moving_target and
/// opponent.
void registerAll(EnvironmentRegistry& registry);
/// Adds static_target and moving_target (environments/static_target.cpp).
void registerStaticTargets(EnvironmentRegistry& registry);
/// Adds opponent (environments/opponent.cpp).
void registerOpponent(EnvironmentRegistry& registry);

/// `opponent`: the target is another avatar of the same graph, standing at e.position on
/// the ground and facing e.heading (speed 0). After each of the avatar's actions it has
/// walked toward the avatar's end position at `speed` (pursue), stopping `stopDistance`
/// from it, and turned toward it by at most turnRate x the action's duration; all seen
/// from the action's end. Its facing turns with the avatar frame, so it is a grid's
/// interpolated heading axis, not a layer.
class Opponent final : public EnvironmentModel {
 public:
  Opponent(bool pursue, double speed, double stopDistance, double turnRate)
      : pursue_(pursue), speed_(speed), stopDistance_(stopDistance), turnRate_(turnRate) {}
  std::string type() const override { return "opponent"; }
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;
  bool keepsSpeed() const override { return true; }  // always 0: the layer of a polar_velocity grid with speeds: 1
  TargetState draw(const Eigen::Vector3d& position, Rng&) const override;
  bool faces() const override { return true; }
  bool pursues() const { return pursue_; }
  double stopDistance() const { return stopDistance_; }

 private:
  bool pursue_;
  double speed_, stopDistance_, turnRate_;  // m/s, m, rad/s
};

}  // namespace mgrl::environments
