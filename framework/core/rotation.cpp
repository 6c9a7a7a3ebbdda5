#include "mgrl/core/rotation.hpp"

#include <cassert>
#include <cmath>
#include <numbers>

namespace mgrl {

char axisLetter(Axis axis) { return "XYZ"[static_cast<int>(axis)]; }

Eigen::Quaterniond axisRotation(Axis axis, double radians) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(radians, Eigen::Vector3d::Unit(static_cast<int>(axis))));
}

Eigen::Quaterniond composeEuler(std::span<const Axis> axes, std::span<const double> radians) {
  assert(axes.size() == radians.size());
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (std::size_t i = 0; i < axes.size(); ++i) q = q * axisRotation(axes[i], radians[i]);
  return q;
}

namespace {

double wrapNear(double angle, double reference) {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  return angle + kTwoPi * std::round((reference - angle) / kTwoPi);
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

}  // namespace

namespace {

// Principal solution, with `lastAtLock` used for the last angle at gimbal lock.
std::array<double, 3> principal(const Eigen::Quaterniond& q, const std::array<Axis, 3>& axes, double lastAtLock) {
  const int i = static_cast<int>(axes[0]), j = static_cast<int>(axes[1]), k = static_cast<int>(axes[2]);
  assert(i != j && j != k && i != k);
  // R = Ri(a) Rj(b) Rk(c). With s = +1 for cyclic (i, j, k) and -1 otherwise:
  // R(i,k) = s sin b, R(j,k) = -s sin a cos b, R(k,k) = cos a cos b,
  // R(i,j) = -s cos b sin c, R(i,i) = cos b cos c.
  const double s = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
  const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
  const double sinB = std::clamp(s * r(i, k), -1.0, 1.0);
  const double b = std::asin(sinB);
  double a = 0, c = 0;
  if (std::abs(sinB) < 1.0 - 1e-12) {
    a = std::atan2(-s * r(j, k), r(k, k));
    c = std::atan2(-s * r(i, j), r(i, i));
  } else {
    // Gimbal lock: only a +/- c is determined; keep c from the previous frame. The
    // remaining rotation Ri(a) then follows from R * Rk(-c) * Rj(-b).
    c = lastAtLock;
    const Eigen::Matrix3d m =
        (q.normalized() * axisRotation(axes[2], -c) * axisRotation(axes[1], -b)).toRotationMatrix();
    // m is a rotation about axis i: with (i, p, n) cyclic, m(n, p) = sin a, m(p, p) = cos a.
    const int p = (i + 1) % 3, n = (i + 2) % 3;
    a = std::atan2(m(n, p), m(p, p));
  }
  return {a, b, c};
}

}  // namespace

std::array<double, 3> principalEuler(const Eigen::Quaterniond& q, const std::array<Axis, 3>& axes) {
  return principal(q, axes, 0.0);
}

std::array<double, 3> decomposeEuler(const Eigen::Quaterniond& q, const std::array<Axis, 3>& axes,
                                     const std::array<double, 3>& previous) {
  const auto [a, b, c] = principal(q, axes, previous[2]);
  const std::array<double, 3> first{a, b, c};
  const std::array<double, 3> second{a + std::numbers::pi, std::numbers::pi - b, c + std::numbers::pi};
  std::array<double, 3> best = first;
  double bestDistance = 1e300;
  for (const auto& candidate : {first, second}) {
    std::array<double, 3> shifted{wrapNear(candidate[0], previous[0]),
                                  wrapNear(candidate[1], previous[1]),
                                  wrapNear(candidate[2], previous[2])};
    const double d = distance(shifted, previous);
    if (d < bestDistance) {
      bestDistance = d;
      best = shifted;
    }
  }
  return best;
}

}  // namespace mgrl
