// polar_velocity: the grid of a moving target. The paper's polar grid (sec. 6.4)
// over the target's ground position, a third axis for the heading of its velocity in the
// avatar frame, and the speed as layers: a moving_target keeps its speed, so every backup
// from a vertex stays in the vertex's layer and learners interpolate in 3-D, as on the
// paper's grids; a decision between two speeds interpolates across the two layers.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "discretizers.hpp"

namespace mgrl::discretizers {

namespace {

class PolarVelocity final : public Discretizer {
 public:
  PolarVelocity(const Params& p, const StateActionModel& m) {
    const Bounds b = chosenBounds(p, m, false);
    height_ = p.choice("height_from") == "centroid" ? static_cast<double>(m.centroid[1]) : p.number("height");
    const auto speeds = static_cast<std::size_t>(p.integer("speeds"));
    const double top = p.number("max_speed");
    std::vector<double> layers = speeds == 1 ? std::vector<double>{0.0} : evenVertices(0, top, speeds, false);
    setAxes({angleAxis(b.angle[0], b.angle[1], static_cast<std::size_t>(p.integer("sectors"))),
             evenAxis(AxisRole::Distance, b.distance[0], b.distance[1], p.integer("rings")),
             GridAxis{AxisRole::Heading,
                      evenVertices(-M_PI, M_PI, static_cast<std::size_t>(p.integer("headings")), true), true}});
    setLayers(GridAxis{AxisRole::Speed, std::move(layers), false});
  }
  std::string type() const override { return "polar_velocity"; }
  std::array<double, 3> coordinates(const TargetState& e) const override {
    return {std::atan2(e.position.x(), e.position.z()), std::hypot(e.position.x(), e.position.z()), e.heading};
  }
  Eigen::Vector3d position(const std::array<double, 3>& c) const override {
    return {c[1] * std::sin(c[0]), height_, c[1] * std::cos(c[0])};
  }
  TargetState state(const std::array<double, 3>& c) const override { return {position(c), 0, c[2]}; }
  nlohmann::json describe() const override {
    nlohmann::json d = Discretizer::describe();
    d["height"] = height_;
    return d;
  }

 private:
  double height_ = 0;
};

}  // namespace

void registerPolarVelocity(DiscretizerRegistry& registry) {
  registry.add(
      {"polar_velocity",
       "a moving target: its ground position (angle x distance, as polar2d) and the heading of its velocity in the "
       "avatar frame, multilinear, in one layer per speed (a moving_target keeps its speed, so learning stays 3-D)",
       withBounds(
           {ParamSpec::integer("sectors", 13, 2, 10000, "vertices", "angle vertices; wrap around over 360 deg"),
            ParamSpec::integer("rings", 5, 2, 10000, "vertices", "distance vertices"),
            ParamSpec::integer("headings", 8, 2, 10000, "vertices", "velocity heading vertices over the full circle"),
            ParamSpec::integer("speeds", 3, 1, 1000, "layers", "speed layers from 0 to max_speed (1: speed 0 only)"),
            ParamSpec::number("max_speed", 1.0, 0.01, 20, "m/s", "the top speed layer"),
            ParamSpec::choice("height_from", "centroid", {"centroid", "given"},
                              "the target's height at the vertices: centroid: the effective hitting points' "
                              "centroid (the height eval places targets at); given: `height`"),
            ParamSpec::number("height", 1.5, -10, 10, "m", "height_from: given: the target's height")},
           {.heights = false}),
       [](const Params& p, const StateActionModel& m) { return std::make_unique<PolarVelocity>(p, m); }});
}

}  // namespace mgrl::discretizers
