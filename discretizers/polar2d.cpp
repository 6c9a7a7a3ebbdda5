// polar2d: the approach behaviour's grid (paper sec. 6.4: "5 x 13 within 2 m").
#include <cmath>

#include <fmt/format.h>

#include "discretizers.hpp"

namespace mgrl::discretizers {

namespace {

/// Axes: angle theta = atan2(x, z) (0 straight ahead, positive to the left), then ground
/// distance. Vertex counts, not cells: `rings` distances from min_radius to radius and
/// `sectors` angles; sectors covering 360 degrees wrap around.
class Polar2d final : public Discretizer {
 public:
  explicit Polar2d(const Params& p) {
    const double radius = p.number("radius"), minRadius = p.number("min_radius");
    if (!(minRadius < radius))
      p.fail("min_radius", fmt::format("expected less than radius ({} m), found {} m", radius, minRadius));
    const double from = p.number("angle_min") * kDeg, to = p.number("angle_max") * kDeg;
    if (!(from < to)) p.fail("angle_max", "expected more than angle_min");
    setAxes({angleAxis(from, to, static_cast<std::size_t>(p.integer("sectors"))),
             evenAxis(AxisRole::Distance, minRadius, radius, p.integer("rings"))});
  }
  std::string type() const override { return "polar2d"; }
  std::array<double, 3> coordinates(const TargetState& state) const override {
    const Eigen::Vector3d& e = state.position;
    return {std::atan2(e.x(), e.z()), std::hypot(e.x(), e.z()), 0};
  }
  Eigen::Vector3d position(const std::array<double, 3>& c) const override {
    return {c[1] * std::sin(c[0]), 0, c[1] * std::cos(c[0])};
  }
};

}  // namespace

void registerPolar2d(DiscretizerRegistry& registry) {
  registry.add({"polar2d",
                "ground position of the target around the avatar: rings x sectors within a radius (paper: 5 x 13 "
                "within 2 m); multilinear in (angle, distance)",
                {ParamSpec::number("radius", 2.0, 0.05, 1000, "m", "outer ring"),
                 ParamSpec::number("min_radius", 0.0, 0, 1000, "m", "inner ring (0: the avatar's position)"),
                 ParamSpec::integer("rings", 5, 2, 10000, "vertices", "distance vertices from min_radius to radius"),
                 ParamSpec::integer("sectors", 13, 2, 10000, "vertices", "angle vertices; wrap around over 360 deg"),
                 ParamSpec::number("angle_min", -180, -360, 360, "deg", "first angle (0 straight ahead, + left)"),
                 ParamSpec::number("angle_max", 180, -360, 360, "deg",
                                   "last angle; angle_max - angle_min = 360 covers the full circle")},
                [](const Params& p, const StateActionModel&) { return std::make_unique<Polar2d>(p); }});
}

}  // namespace mgrl::discretizers
