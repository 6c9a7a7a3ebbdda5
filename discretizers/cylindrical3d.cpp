// cylindrical3d: the hit behaviour's grid (paper sec. 6.4: "10 x 10 x 4" over the
// bounding volume of the effective hitting points).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "discretizers.hpp"

namespace mgrl::discretizers {

namespace {}  // namespace

// The bounding volume, in (angle, distance, height), of the effective hitting points as
// seen from the decision that leads to them: a target there can be hit by some action.
Bounds boundsOfHits(const Params& p, const StateActionModel& m) {
  if (m.hits.size() < 2)
    p.fail("bounds", fmt::format("expected at least 2 effective hitting points in the graph's actions to take the "
                                 "bounds from, found {}; set bounds: given with angle_min ... height_max",
                                 m.hits.size()));
  Bounds b{{INFINITY, -INFINITY}, {INFINITY, -INFINITY}, {INFINITY, -INFINITY}};
  for (const ActionHit& h : m.hits) {
    const double x = h.x, z = h.z;  // in double, as coordinates() computes them
    const double angle = std::atan2(x, z), distance = std::hypot(x, z);
    b.angle[0] = std::min(b.angle[0], angle);
    b.angle[1] = std::max(b.angle[1], angle);
    b.distance[0] = std::min(b.distance[0], distance);
    b.distance[1] = std::max(b.distance[1], distance);
    b.height[0] = std::min(b.height[0], static_cast<double>(h.y));
    b.height[1] = std::max(b.height[1], static_cast<double>(h.y));
  }
  const double margin = p.number("margin"), angleMargin = p.number("angle_margin") * kDeg;
  b.angle[0] -= angleMargin;
  b.angle[1] += angleMargin;
  b.distance[0] = std::max(0.0, b.distance[0] - margin);
  b.distance[1] += margin;
  b.height[0] -= margin;
  b.height[1] += margin;
  if (b.angle[1] - b.angle[0] > 2 * M_PI) {
    b.angle[0] = -M_PI;
    b.angle[1] = M_PI;
  }
  for (const auto* range : {b.angle, b.distance, b.height})
    if (!(range[1] > range[0]))
      p.fail("bounds", "expected the effective hitting points to span a volume, found them all on one plane; set "
                       "bounds: given");
  return b;
}

Bounds givenBounds(const Params& p) {
  Bounds b{{p.number("angle_min") * kDeg, p.number("angle_max") * kDeg},
           {p.number("distance_min"), p.number("distance_max")},
           {p.number("height_min"), p.number("height_max")}};
  if (!(b.angle[1] > b.angle[0])) p.fail("angle_max", "expected more than angle_min");
  if (b.angle[1] - b.angle[0] > 2 * M_PI + 1e-9) p.fail("angle_max", "expected at most 360 degrees above angle_min");
  if (!(b.distance[1] > b.distance[0])) p.fail("distance_max", "expected more than distance_min");
  if (!(b.height[1] > b.height[0])) p.fail("height_max", "expected more than height_min");
  return b;
}

namespace {

class Cylindrical3d final : public Discretizer {
 public:
  Cylindrical3d(const Params& p, const StateActionModel& m) {
    const Bounds b = p.choice("bounds") == "hits" ? boundsOfHits(p, m) : givenBounds(p);
    const bool wrap = b.angle[1] - b.angle[0] >= 2 * M_PI - 1e-9;
    const auto angles = static_cast<std::size_t>(p.integer("angles"));
    setAxes(
        {GridAxis{AxisRole::Angle, evenVertices(b.angle[0], wrap ? b.angle[0] + 2 * M_PI : b.angle[1], angles, wrap),
                  wrap},
         GridAxis{AxisRole::Distance,
                  evenVertices(b.distance[0], b.distance[1], static_cast<std::size_t>(p.integer("distances")), false),
                  false},
         GridAxis{AxisRole::Height,
                  evenVertices(b.height[0], b.height[1], static_cast<std::size_t>(p.integer("heights")), false),
                  false}});
  }
  std::string type() const override { return "cylindrical3d"; }
  std::array<double, 3> coordinates(const TargetState& state) const override {
    const Eigen::Vector3d& e = state.position;
    return {std::atan2(e.x(), e.z()), std::hypot(e.x(), e.z()), e.y()};
  }
  Eigen::Vector3d position(const std::array<double, 3>& c) const override {
    return {c[1] * std::sin(c[0]), c[2], c[1] * std::cos(c[0])};
  }
};

}  // namespace

void registerCylindrical3d(DiscretizerRegistry& registry) {
  registry.add(
      {"cylindrical3d",
       "target position around the avatar as angle x distance x height (paper: 10 x 10 x 4 over the bounding "
       "volume of the effective hitting points); multilinear",
       {ParamSpec::integer("angles", 10, 2, 10000, "vertices", "angle vertices"),
        ParamSpec::integer("distances", 10, 2, 10000, "vertices", "ground distance vertices"),
        ParamSpec::integer("heights", 4, 2, 10000, "vertices", "height vertices"),
        ParamSpec::choice("bounds", "hits", {"hits", "given"},
                          "hits: the bounding volume of the graph's effective hitting points; given: the *_min/*_max "
                          "parameters"),
        ParamSpec::number("margin", 0.0, 0, 10, "m", "bounds: hits: widen distance and height by this much"),
        ParamSpec::number("angle_margin", 0.0, 0, 180, "deg", "bounds: hits: widen the angle range by this much"),
        ParamSpec::number("angle_min", -90, -360, 360, "deg", "bounds: given: first angle (0 ahead, + left)"),
        ParamSpec::number("angle_max", 90, -360, 360, "deg", "bounds: given: last angle"),
        ParamSpec::number("distance_min", 0.2, 0, 100, "m", "bounds: given: nearest ground distance"),
        ParamSpec::number("distance_max", 1.0, 0, 100, "m", "bounds: given: farthest ground distance"),
        ParamSpec::number("height_min", 0.8, -10, 10, "m", "bounds: given: lowest height"),
        ParamSpec::number("height_max", 1.8, -10, 10, "m", "bounds: given: highest height")},
       [](const Params& p, const StateActionModel& m) { return std::make_unique<Cylindrical3d>(p, m); }});
}

}  // namespace mgrl::discretizers
