// cylindrical3d: the hit behaviour's grid (paper sec. 6.4: "10 x 10 x 4" over the
// bounding volume of the effective hitting points).
#include <cmath>

#include "discretizers.hpp"

namespace mgrl::discretizers {

namespace {

class Cylindrical3d final : public Discretizer {
 public:
  Cylindrical3d(const Params& p, const StateActionModel& m) {
    const Bounds b = chosenBounds(p, m);
    setAxes({angleAxis(b.angle[0], b.angle[1], static_cast<std::size_t>(p.integer("angles"))),
             evenAxis(AxisRole::Distance, b.distance[0], b.distance[1], p.integer("distances")),
             evenAxis(AxisRole::Height, b.height[0], b.height[1], p.integer("heights"))});
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
  registry.add({"cylindrical3d",
                "target position around the avatar as angle x distance x height (paper: 10 x 10 x 4 over the bounding "
                "volume of the effective hitting points); multilinear",
                withBounds({ParamSpec::integer("angles", 10, 2, 10000, "vertices", "angle vertices"),
                            ParamSpec::integer("distances", 10, 2, 10000, "vertices", "ground distance vertices"),
                            ParamSpec::integer("heights", 4, 2, 10000, "vertices", "height vertices")},
                           {.bounds = "hits", .angle = {-90, 90}, .distance = {0.2, 1.0}}),
                [](const Params& p, const StateActionModel& m) { return std::make_unique<Cylindrical3d>(p, m); }});
}

}  // namespace mgrl::discretizers
