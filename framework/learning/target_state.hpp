#pragma once
/// \file
/// The environment state a behaviour's grid, reward and environment model see (DESIGN.md
/// sec. 4): where the target is in the avatar frame at a decision (+Z facing, +X left, Y up;
/// metres) and how it moves on the ground. A static target has speed 0; a `moving_target`
/// keeps its speed for a whole episode and its heading turns with the avatar.
#include <cmath>
#include <cstdint>

#include <Eigen/Core>

namespace mgrl {

struct TargetState {
  Eigen::Vector3d position{0, 0, 0};
  double speed = 0;    ///< ground speed, m/s (>= 0)
  double heading = 0;  ///< direction of the ground velocity in the avatar frame, rad: atan2(vx, vz)
  /// A `learned_opponent`'s discrete state (its graph state and phase, a grid layer), -1 for
  /// every other environment model.
  std::int32_t opponent = -1;

  TargetState() = default;
  /// A static target at `p` (implicit: every static-target call site passes a position, or
  /// an Eigen expression of one).
  template <class Derived>
  TargetState(const Eigen::MatrixBase<Derived>& p) : position(p) {}  // NOLINT(google-explicit-constructor)
  TargetState(double x, double y, double z) : position(x, y, z) {}
  TargetState(const Eigen::Vector3d& p, double speed_, double heading_) : position(p), speed(speed_), heading(heading_) {}

  bool moving() const { return speed != 0; }
  /// The ground velocity in the avatar frame, m/s.
  Eigen::Vector3d velocity() const { return {speed * std::sin(heading), 0, speed * std::cos(heading)}; }
  /// Where the target is `seconds` after the decision, in the decision's avatar frame: the
  /// position itself, bit for bit, when it does not move (the paper's static target).
  Eigen::Vector3d at(double seconds) const { return moving() ? Eigen::Vector3d(position + seconds * velocity()) : position; }
};

}  // namespace mgrl
