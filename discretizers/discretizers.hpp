#pragma once
/// \file
/// The discretizer plugins (paper sec. 4.2, 6.4): `polar2d` for approaching (the target's
/// ground position around the avatar) and `cylindrical3d` for hitting (angle, distance and
/// height over the volume the avatar's effective punches reach).
#include <cmath>

#include "mgrl/learning/discretizer.hpp"

namespace mgrl::discretizers {

/// Radians per degree: the discretizers' angle parameters are given in degrees.
inline constexpr double kDeg = M_PI / 180;

/// Adds polar2d, cylindrical3d, kd_tree and polar_velocity.
void registerAll(DiscretizerRegistry& registry);

/// Evenly spaced vertices from `from` to `to`; with `wrap`, the last one stops a step
/// short of `to` (which is `from` again, a full turn on).
std::vector<double> evenVertices(double from, double to, std::size_t count, bool wrap);

/// A box in (angle, distance, height): radians, metres.
struct Bounds {
  double angle[2], distance[2], height[2];
};
/// The bounding volume of the model's effective hitting points as seen from their
/// decisions, widened by the parameters `margin` and `angle_margin` (deg); throws the
/// parameters' ConfigError if there are fewer than 2 hits or they span no volume.
Bounds boundsOfHits(const Params& p, const StateActionModel& m);
/// The box of the parameters angle_min ... height_max (deg and m), checked.
Bounds givenBounds(const Params& p);

}  // namespace mgrl::discretizers

namespace mgrl::discretizers {
void registerPolar2d(DiscretizerRegistry& registry);
void registerCylindrical3d(DiscretizerRegistry& registry);
void registerKdTree(DiscretizerRegistry& registry);
void registerPolarVelocity(DiscretizerRegistry& registry);
}  // namespace mgrl::discretizers
