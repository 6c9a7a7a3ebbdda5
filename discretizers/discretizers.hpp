#pragma once
/// \file
/// The discretizer plugins (paper sec. 4.2, 6.4): `polar2d` for approaching (the target's
/// ground position around the avatar) and `cylindrical3d` for hitting (angle, distance and
/// height over the volume the avatar's effective punches reach).
#include "mgrl/learning/discretizer.hpp"

namespace mgrl::discretizers {

/// Adds polar2d and cylindrical3d.
void registerAll(DiscretizerRegistry& registry);

/// Evenly spaced vertices from `from` to `to`; with `wrap`, the last one stops a step
/// short of `to` (which is `from` again, a full turn on).
std::vector<double> evenVertices(double from, double to, std::size_t count, bool wrap);

}  // namespace mgrl::discretizers

namespace mgrl::discretizers {
void registerPolar2d(DiscretizerRegistry& registry);
void registerCylindrical3d(DiscretizerRegistry& registry);
}  // namespace mgrl::discretizers
