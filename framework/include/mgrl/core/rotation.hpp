#pragma once
/// \file
/// Rotations about coordinate axes and Euler-angle sequences as BVH and ASF use them.
/// A sequence "Z Y X" means R = Rz(a0) * Ry(a1) * Rx(a2) acting on column vectors, which
/// is how a BVH `CHANNELS ... Zrotation Yrotation Xrotation` line is read.

#include <array>
#include <span>

#include <Eigen/Geometry>

namespace mgrl {

enum class Axis : unsigned char { X = 0, Y = 1, Z = 2 };

/// Letter of an axis: 'X', 'Y' or 'Z'.
char axisLetter(Axis axis);

/// Rotation by `radians` about `axis`.
Eigen::Quaterniond axisRotation(Axis axis, double radians);

/// R = R(axes[0], angles[0]) * R(axes[1], angles[1]) * ... (radians). Any number of axes.
Eigen::Quaterniond composeEuler(std::span<const Axis> axes, std::span<const double> radians);

/// The principal Euler angles (radians) of `q` for three distinct `axes`: middle angle in
/// [-pi/2, pi/2], outer angles in (-pi, pi], as most BVH files store them (CMU and SNU do).
/// At gimbal lock the last angle is 0.
std::array<double, 3> principalEuler(const Eigen::Quaterniond& q, const std::array<Axis, 3>& axes);

/// Decomposes `q` into angles (radians) for three distinct `axes` so that
/// composeEuler(axes, result) == q. Of the two solutions, and their 2*pi shifts, returns
/// the one closest to `previous` in summed absolute angle (zeros: the smallest angles).
/// Keeps exported curves continuous. Requires distinct axes.
std::array<double, 3> decomposeEuler(const Eigen::Quaterniond& q, const std::array<Axis, 3>& axes,
                                     const std::array<double, 3>& previous = {0, 0, 0});

constexpr double kDegToRad = 0.017453292519943295769;
constexpr double kRadToDeg = 57.295779513082320877;

}  // namespace mgrl
