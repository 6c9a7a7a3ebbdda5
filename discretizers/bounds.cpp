// What the grids over a box share: the box of the effective hitting points or of given
// bounds (paper sec. 6.4: the hit grid spans "the bounding volume of the effective hitting
// points"), its parameters, and evenly spaced axes.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "discretizers.hpp"

namespace mgrl::discretizers {

std::vector<double> evenVertices(double from, double to, std::size_t count, bool wrap) {
  std::vector<double> v(count);
  const double steps = static_cast<double>(wrap ? count : count - 1);
  for (std::size_t i = 0; i < count; ++i) v[i] = from + (to - from) * static_cast<double>(i) / steps;
  if (!wrap) v.back() = to;  // exactly: a point on the bound is inside
  return v;
}

GridAxis angleAxis(double from, double to, std::size_t count) {
  const bool wrap = to - from >= 2 * M_PI - 1e-9;
  return {AxisRole::Angle, evenVertices(from, wrap ? from + 2 * M_PI : to, count, wrap), wrap};
}

GridAxis evenAxis(AxisRole role, double from, double to, long long count) {
  return {role, evenVertices(from, to, static_cast<std::size_t>(count), false), false};
}

// The bounding volume, in (angle, distance, height), of the effective hitting points as
// seen from the decision that leads to them: a target there can be hit by some action.
Bounds boundsOfHits(const Params& p, const StateActionModel& m, bool heights) {
  if (m.hits.size() < 2)
    p.fail("bounds", fmt::format("expected at least 2 effective hitting points in the graph's actions to take the "
                                 "bounds from, found {}; set bounds: given with angle_min ... {}",
                                 m.hits.size(), heights ? "height_max" : "distance_max"));
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
    if (!(range[1] > range[0]) && (heights || range != b.height))
      p.fail("bounds", heights ? "expected the effective hitting points to span a volume, found them all on one "
                                 "plane; set bounds: given"
                               : "expected the effective hitting points to span an area, found them all at one angle "
                                 "or one distance; set bounds: given");
  return b;
}

Bounds givenBounds(const Params& p, bool heights) {
  Bounds b{{p.number("angle_min") * kDeg, p.number("angle_max") * kDeg},
           {p.number("distance_min"), p.number("distance_max")},
           {heights ? p.number("height_min") : 0, heights ? p.number("height_max") : 0}};
  if (!(b.angle[1] > b.angle[0])) p.fail("angle_max", "expected more than angle_min");
  if (b.angle[1] - b.angle[0] > 2 * M_PI + 1e-9) p.fail("angle_max", "expected at most 360 degrees above angle_min");
  if (!(b.distance[1] > b.distance[0]))
    p.fail("distance_max",
           fmt::format("expected more than distance_min ({} m), found {} m", b.distance[0], b.distance[1]));
  if (heights && !(b.height[1] > b.height[0]))
    p.fail("height_max", fmt::format("expected more than height_min ({} m), found {} m", b.height[0], b.height[1]));
  return b;
}

// The box's parameters are checked as a whole: a key the chosen `bounds` does not read is
// refused rather than ignored (a range given beside `bounds: hits` would change nothing).
Bounds chosenBounds(const Params& p, const StateActionModel& m, bool heights) {
  const bool hits = p.choice("bounds") == "hits";
  std::vector<const char*> unread = {"margin", "angle_margin"};
  if (hits) {
    unread = {"angle_min", "angle_max", "distance_min", "distance_max"};
    if (heights) unread.insert(unread.end(), {"height_min", "height_max"});
  }
  for (const char* key : unread)
    if (p.given(key))
      p.fail(key, fmt::format("expected no {} with bounds: {} (it applies to bounds: {} only); remove it or set "
                              "bounds: {}",
                              key, hits ? "hits" : "given", hits ? "given" : "hits", hits ? "given" : "hits"));
  return hits ? boundsOfHits(p, m, heights) : givenBounds(p, heights);
}

std::vector<ParamSpec> withBounds(std::vector<ParamSpec> own, const BoundsDefaults& d) {
  const char* last = d.heights ? "height_max" : "distance_max";
  own.insert(
      own.end(),
      {ParamSpec::choice("bounds", d.bounds, {"hits", "given"},
                         fmt::format("hits: the bounding {} of the graph's effective hitting points; given: angle_min "
                                     "... {}",
                                     d.heights ? "volume (angle, distance, height)" : "area (angle, distance)", last)),
       ParamSpec::number("margin", 0.0, 0, 10, "m",
                         d.heights ? "bounds: hits: widen distance and height by this much"
                                   : "bounds: hits: widen the distances by this much"),
       ParamSpec::number("angle_margin", 0.0, 0, 180, "deg", "bounds: hits: widen the angle range by this much"),
       ParamSpec::number("angle_min", d.angle[0], -360, 360, "deg", "bounds: given: first angle (0 ahead, + left)"),
       ParamSpec::number("angle_max", d.angle[1], -360, 360, "deg",
                         "bounds: given: last angle; 360 degrees above angle_min wrap around"),
       ParamSpec::number("distance_min", d.distance[0], d.lowestDistance, 100, "m",
                         "bounds: given: nearest ground distance"),
       ParamSpec::number("distance_max", d.distance[1], d.lowestDistance, 100, "m",
                         "bounds: given: farthest ground distance")});
  if (d.heights)
    own.insert(own.end(),
               {ParamSpec::number("height_min", d.height[0], -10, 10, "m", "bounds: given: lowest height"),
                ParamSpec::number("height_max", d.height[1], -10, 10, "m", "bounds: given: highest height")});
  return own;
}

}  // namespace mgrl::discretizers
