#pragma once
/// \file
/// The environment state a behaviour's grid, reward and environment model see (DESIGN.md
/// sec. 4): where the target is in the avatar frame at a decision (+Z facing, +X left, Y up;
/// metres) and how it moves on the ground. A static target has speed 0; a `moving_target`
/// keeps its speed and its turn rate for a whole episode, and its heading turns with the
/// avatar (and, at a turn rate, with the target's own arc).
#include <cmath>
#include <cstdint>

#include <Eigen/Core>

namespace mgrl {

struct TargetState {
  Eigen::Vector3d position{0, 0, 0};
  double speed = 0;    ///< ground speed, m/s (>= 0)
  double heading = 0;  ///< direction of the ground velocity in the avatar frame, rad: atan2(vx, vz)
  /// How fast the velocity's direction turns, rad/s (positive: towards +X, the avatar
  /// frame's left); 0 for a straight line. A target at speed v and turn rate w runs round a
  /// circle of radius v / |w|.
  double turnRate = 0;
  /// A `learned_opponent`'s discrete state (its graph state and phase, a grid layer), -1 for
  /// every other environment model.
  std::int32_t opponent = -1;
  /// The stance the fighter holds (a world with stances draws one per fighter and
  /// holds it a while; behaviours with `stance: k` are active only while it is k), -1 for
  /// none (every behaviour active). It belongs to the fighter, not to the target's motion:
  /// environment models build their next state without it, and nextHoldingStance() keeps it.
  std::int32_t stance = -1;

  TargetState() = default;
  /// A static target at `p` (implicit: every static-target call site passes a position, or
  /// an Eigen expression of one).
  template <class Derived>
  TargetState(const Eigen::MatrixBase<Derived>& p) : position(p) {}  // NOLINT(google-explicit-constructor)
  TargetState(double x, double y, double z) : position(x, y, z) {}
  TargetState(const Eigen::Vector3d& p, double speed_, double heading_)
      : position(p), speed(speed_), heading(heading_) {}

  bool moving() const { return speed != 0; }
  /// The ground velocity in the avatar frame, m/s.
  Eigen::Vector3d velocity() const { return {speed * std::sin(heading), 0, speed * std::cos(heading)}; }
  /// Where the target is `seconds` after the decision, in the decision's avatar frame: the
  /// position itself, bit for bit, when it does not move (the paper's static target); a
  /// straight line at turn rate 0, bit for bit as before turning targets; else the arc
  /// p + (v / w) (cos h - cos(h + w t), 0, sin(h + w t) - sin h), the integral of the
  /// velocity v (sin(h + w s), 0, cos(h + w s)) over s in [0, t].
  Eigen::Vector3d at(double seconds) const {
    if (!moving()) return position;
    if (turnRate == 0) return position + seconds * velocity();
    const double r = speed / turnRate, later = heading + turnRate * seconds;
    return position +
           Eigen::Vector3d(r * (std::cos(heading) - std::cos(later)), 0, r * (std::sin(later) - std::sin(heading)));
  }
  /// The velocity's heading `seconds` after the decision, in the decision's avatar frame
  /// (not wrapped): the heading itself, bit for bit, at turn rate 0.
  double headingAt(double seconds) const { return turnRate == 0 ? heading : heading + turnRate * seconds; }
};

}  // namespace mgrl
