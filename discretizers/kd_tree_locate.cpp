// kd_tree's runtime side (kd_tree.hpp): a target's grid coordinates, the leaf that holds
// them and their fractions in it, and the positions of vertices and leaf centres. Every
// learner's backup and every runtime decision on a kd_tree goes through locate().
#include <algorithm>
#include <cmath>

#include "kd_tree.hpp"

namespace mgrl::discretizers {

std::array<double, 3> KdTree::coordinates(const TargetState& state) const {
  const Eigen::Vector3d& e = state.position;
  const double angle = std::atan2(e.x(), e.z()), distance = std::hypot(e.x(), e.z());
  if (coordinates_ == 1) return {std::copysign(distance, e.z()), 0, 0};
  return {angle, distance, coordinates_ == 3 ? e.y() : 0.0};
}

Eigen::Vector3d KdTree::position(const std::array<double, 3>& c) const {
  if (coordinates_ == 1) return {0, height_, c[0]};
  return {c[1] * std::sin(c[0]), coordinates_ == 3 ? c[2] : height_, c[1] * std::cos(c[0])};
}

inline std::size_t KdTree::rootOf(const std::array<double, 3>& c) const {
  std::size_t root = 0, stride = 1;
  for (int i = 0; i < dimension_; ++i) {
    std::uint64_t j = 0;
    if (roots_[i] > 1) {
      j = static_cast<std::uint64_t>(std::clamp((c[i] - lo_[i]) / span_[i] * static_cast<double>(roots_[i]), 0.0,
                                                static_cast<double>(roots_[i] - 1)));
      // The exact boundary coordinates settle round-off, as for a split.
      while (j > 0 && c[i] < coordinate(i, j * rootKeys(i))) --j;
      while (j + 1 < roots_[i] && c[i] >= coordinate(i, (j + 1) * rootKeys(i))) ++j;
    }
    root += static_cast<std::size_t>(j) * stride;
    stride *= static_cast<std::size_t>(roots_[i]);
  }
  return root;
}

inline GridCell KdTree::find(const std::array<double, 3>& c) const {
  std::size_t n = rootCount_ > 1 ? rootOf(c) : 0;
  while (axis_[n] >= 0) n = static_cast<std::size_t>(children_[2 * n + (c[axis_[n]] >= splitCoordinate_[n] ? 1 : 0)]);
  GridCell out;
  const std::int32_t leaf = nodeLeaf_[n];
  out.cell = static_cast<std::uint32_t>(leaf);
  for (int i = 0; i < dimension_; ++i) {
    const double lo = leafLo_[3 * leaf + i], hi = leafHi_[3 * leaf + i];
    out.frac[i] = static_cast<float>(std::clamp((c[i] - lo) / (hi - lo), 0.0, 1.0));
  }
  return out;
}

bool KdTree::locate(const TargetState& e, GridCell& out) const {
  std::array<double, 3> c = coordinates(e);
  for (int i = 0; i < dimension_; ++i) {
    if (!std::isfinite(c[i])) return false;
    if (wraps_[i])
      c[i] = wrapped(i, c[i]);
    else if (!(c[i] >= lo_[i] && c[i] <= lo_[i] + span_[i]))
      return false;
  }
  out = find(c);
  return true;
}

GridCell KdTree::locateClamped(const TargetState& e) const {
  std::array<double, 3> c = coordinates(e);
  for (int i = 0; i < dimension_; ++i) {
    if (std::isnan(c[i])) c[i] = lo_[i];
    c[i] = wraps_[i] ? wrapped(i, c[i]) : std::clamp(c[i], lo_[i], lo_[i] + span_[i]);
  }
  return find(c);
}

TargetState KdTree::vertexState(std::size_t v) const {
  std::array<double, 3> c{0, 0, 0};
  for (int i = 0; i < dimension_; ++i) c[i] = vertexCoordinates_[v * dimension_ + i];
  return position(c);
}

Eigen::Vector3d KdTree::cellCentre(std::uint32_t cell) const {
  std::array<double, 3> c{0, 0, 0};
  for (int i = 0; i < dimension_; ++i) c[i] = 0.5 * (leafLo_[3 * cell + i] + leafHi_[3 * cell + i]);
  return position(c);
}

}  // namespace mgrl::discretizers
