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
/// An angle axis of `count` even vertices from `from` to `to` (radians); a full turn wraps.
GridAxis angleAxis(double from, double to, std::size_t count);
/// An axis of `count` even vertices from `from` to `to` that does not wrap.
GridAxis evenAxis(AxisRole role, double from, double to, long long count);

/// A box in (angle, distance, height): radians, metres.
struct Bounds {
  double angle[2], distance[2], height[2];
};
/// The bounding volume of the model's effective hitting points as seen from their
/// decisions, widened by the parameters `margin` and `angle_margin` (deg); throws the
/// parameters' ConfigError if there are fewer than 2 hits or they span no volume (no area
/// in angle and distance when not `heights`).
Bounds boundsOfHits(const Params& p, const StateActionModel& m, bool heights = true);
/// The box of the parameters angle_min ... height_max (deg and m; without the heights
/// when not `heights`: then the box's height is [0, 0]), checked.
Bounds givenBounds(const Params& p, bool heights = true);
/// The box the parameter `bounds` chooses: `hits` or `given`.
Bounds chosenBounds(const Params& p, const StateActionModel& m, bool heights = true);

/// The defaults of the box parameters of a grid plug-in (withBounds()).
struct BoundsDefaults {
  const char* bounds = "given";   ///< "hits" or "given"
  double angle[2] = {-180, 180};  ///< deg
  double distance[2] = {0, 2};    ///< m
  double height[2] = {0.8, 1.8};  ///< m
  bool heights = true;            ///< the box has a height axis
  double lowestDistance = 0;      ///< the least distance_min and distance_max allowed
};
/// `own` followed by the box parameters that chosenBounds() reads: bounds, margin,
/// angle_margin, angle_min ... distance_max and, with heights, height_min and height_max.
std::vector<ParamSpec> withBounds(std::vector<ParamSpec> own, const BoundsDefaults& d);

}  // namespace mgrl::discretizers

namespace mgrl::discretizers {
void registerPolar2d(DiscretizerRegistry& registry);
void registerCylindrical3d(DiscretizerRegistry& registry);
void registerKdTree(DiscretizerRegistry& registry);
void registerPolarVelocity(DiscretizerRegistry& registry);
}  // namespace mgrl::discretizers
