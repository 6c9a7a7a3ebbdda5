#include "mgrl/learning/discretizer.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

namespace {

constexpr double kTwoPi = 2 * M_PI;

// Interval of coordinate c on an axis: index of its lower vertex and the fraction towards
// the next one (the first vertex + 2 pi for the last interval of a wrapping axis).
// `inverseStep` > 0 marks evenly spaced vertices, found by arithmetic (the hot path of
// every learner); otherwise by binary search.
inline bool locateOnAxis(const GridAxis& axis, double inverseStep, double c, std::uint32_t& index, float& frac) {
  const std::vector<double>& v = axis.vertices;
  const std::size_t n = v.size();
  if (axis.wraps) {
    if (!std::isfinite(c)) return false;
    if (c < v[0] || c >= v[0] + kTwoPi) {
      c = v[0] + std::fmod(std::fmod(c - v[0], kTwoPi) + kTwoPi, kTwoPi);  // into [v0, v0 + 2 pi)
      if (c >= v[0] + kTwoPi) c = v[0];
    }
    if (c >= v[n - 1]) {
      index = static_cast<std::uint32_t>(n - 1);
      frac = static_cast<float>(std::clamp((c - v[n - 1]) / (v[0] + kTwoPi - v[n - 1]), 0.0, 1.0));
      return true;
    }
  } else if (!(c >= v[0] && c <= v[n - 1])) {
    return false;  // also for NaN
  }
  std::size_t i;
  if (inverseStep > 0) {
    i = static_cast<std::size_t>((c - v[0]) * inverseStep);
    i = std::min(i, n - 2);
    // Round-off at a vertex may land one interval off; the exact comparison settles it.
    if (c < v[i] && i > 0) --i;
    else if (c > v[i + 1] && i + 2 < n) ++i;
  } else {
    const std::size_t upper = static_cast<std::size_t>(std::upper_bound(v.begin(), v.end(), c) - v.begin());
    i = std::min(upper == 0 ? 0 : upper - 1, n - 2);
  }
  index = static_cast<std::uint32_t>(i);
  frac = static_cast<float>(std::clamp((c - v[i]) / (v[i + 1] - v[i]), 0.0, 1.0));
  return true;
}

}  // namespace

void Discretizer::setAxes(std::vector<GridAxis> axes) {
  if (axes.size() < 1 || axes.size() > 3)
    throw Error(fmt::format("{}: expected 1 to 3 axes, found {}", type(), axes.size()));
  vertexCount_ = 1;
  cellCount_ = 1;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const GridAxis& axis = axes[i];
    if (axis.vertices.size() < 2)
      throw Error(fmt::format("{}: {}: expected at least 2 vertices, found {}", type(), axis.name,
                              axis.vertices.size()));
    for (std::size_t k = 0; k < axis.vertices.size(); ++k) {
      if (!std::isfinite(axis.vertices[k]))
        throw Error(fmt::format("{}: {}: expected finite vertex coordinates", type(), axis.name));
      if (k > 0 && !(axis.vertices[k] > axis.vertices[k - 1]))
        throw Error(fmt::format("{}: {}: expected ascending vertex coordinates, found {} after {}", type(), axis.name,
                                axis.vertices[k], axis.vertices[k - 1]));
    }
    if (axis.wraps && !(axis.vertices.back() - axis.vertices.front() < kTwoPi))
      throw Error(fmt::format("{}: {}: a wrapping axis must span less than 360 degrees", type(), axis.name));
    cellsPerAxis_[i] = axis.wraps ? axis.vertices.size() : axis.vertices.size() - 1;
    const std::size_t n = axis.vertices.size();
    const double step = (axis.vertices.back() - axis.vertices.front()) / static_cast<double>(n - 1);
    bool even = true;
    for (std::size_t k = 0; k < n; ++k)
      even = even && std::fabs(axis.vertices[k] - (axis.vertices.front() + step * static_cast<double>(k))) <= 1e-9 * (1 + std::fabs(step));
    inverseStep_[i] = even ? 1 / step : 0;
    vertexCount_ *= axis.vertices.size();
    cellCount_ *= cellsPerAxis_[i];
  }
  // Issue 19: the size is checked before the corner table is made (a 10000 x 10000 polar
  // grid spent 30 s and 3 GB before anything said no).
  if (vertexCount_ > kMaxGridVertices) {
    std::vector<std::string> sizes;
    for (const GridAxis& axis : axes) sizes.push_back(fmt::format("{} {}", axis.vertices.size(), axis.name));
    throw Error(fmt::format("{}: expected a grid of at most {} vertices, found {} ({})", type(), kMaxGridVertices,
                            vertexCount_, fmt::join(sizes, " x ")));
  }
  axes_ = std::move(axes);
  const int d = dimension();
  corners_.assign(cellCount_ << d, 0);
  std::array<std::size_t, 3> n{1, 1, 1};
  for (int i = 0; i < d; ++i) n[i] = axes_[i].vertices.size();
  for (std::size_t c = 0; c < cellCount_; ++c) {
    std::array<std::size_t, 3> idx{0, 0, 0};
    std::size_t rest = c;
    for (int i = 0; i < d; ++i) {
      idx[i] = rest % cellsPerAxis_[i];
      rest /= cellsPerAxis_[i];
    }
    for (int k = 0; k < (1 << d); ++k) {
      std::size_t vertex = 0, stride = 1;
      for (int i = 0; i < d; ++i) {
        const std::size_t j = (idx[i] + (k >> i & 1)) % n[i];
        vertex += j * stride;
        stride *= n[i];
      }
      corners_[(c << d) | k] = static_cast<std::uint32_t>(vertex);
    }
  }
}

void Discretizer::setCells(std::size_t vertexCount, std::size_t cellCount, std::vector<std::uint32_t> corners,
                           HangingVertices hanging) {
  if (corners.size() != cellCount << dimension())
    throw Error(fmt::format("{}: expected {} cell corners, found {}", type(), cellCount << dimension(), corners.size()));
  if (vertexCount > kMaxGridVertices)
    throw Error(fmt::format("{}: expected a grid of at most {} vertices, found {}", type(), kMaxGridVertices,
                            vertexCount));
  vertexCount_ = vertexCount;
  cellCount_ = cellCount;
  corners_ = std::move(corners);
  hanging_ = std::move(hanging);
}

Eigen::Vector3d Discretizer::cellCentre(std::uint32_t) const {
  throw Error(fmt::format("{}: a fixed grid has no adaptive cells", type()));
}

std::unique_ptr<Discretizer> Discretizer::refined(const std::vector<std::uint32_t>&) const {
  throw Error(fmt::format("{}: a fixed grid cannot be refined; use discretizer type kd_tree", type()));
}

std::unique_ptr<Discretizer> Discretizer::withInitialCells(const std::vector<long long>&) const {
  throw Error(fmt::format("{}: a fixed grid has no initial cells to start from; use discretizer type kd_tree", type()));
}

std::unique_ptr<Discretizer> Discretizer::restored(const std::vector<StructureArray>& arrays) const {
  throw Error(fmt::format("{}: a fixed {} grid has no saved structure to restore",
                          arrays.empty() || arrays[0].source.empty() ? type() : arrays[0].source, type()));
}

bool Discretizer::locate(const Eigen::Vector3d& e, GridCell& out) const {
  const std::array<double, 3> c = coordinates(e);
  std::size_t cell = 0, stride = 1;
  for (int i = 0; i < dimension(); ++i) {
    std::uint32_t index = 0;
    if (!locateOnAxis(axes_[i], inverseStep_[i], c[i], index, out.frac[i])) return false;
    cell += index * stride;
    stride *= cellsPerAxis_[i];
  }
  out.cell = static_cast<std::uint32_t>(cell);
  return true;
}

GridCell Discretizer::locateClamped(const Eigen::Vector3d& e) const {
  std::array<double, 3> c = coordinates(e);
  for (int i = 0; i < dimension(); ++i) {
    const GridAxis& axis = axes_[i];
    if (!axis.wraps) c[i] = std::clamp(std::isnan(c[i]) ? axis.vertices.front() : c[i], axis.vertices.front(),
                                       axis.vertices.back());
    else if (std::isnan(c[i])) c[i] = axis.vertices.front();
  }
  GridCell out;
  std::size_t cell = 0, stride = 1;
  for (int i = 0; i < dimension(); ++i) {
    std::uint32_t index = 0;
    locateOnAxis(axes_[i], inverseStep_[i], c[i], index, out.frac[i]);
    cell += index * stride;
    stride *= cellsPerAxis_[i];
  }
  out.cell = static_cast<std::uint32_t>(cell);
  return out;
}

Stencil Discretizer::stencil(const GridCell& cell) const {
  Stencil s;
  const int d = dimension();
  s.size = 1 << d;
  cornerWeights(d, cell.frac, s.weight.data());
  for (int k = 0; k < s.size; ++k) s.vertex[k] = corners_[(static_cast<std::size_t>(cell.cell) << d) | k];
  return s;
}

Eigen::Vector3d Discretizer::vertexPosition(std::size_t v) const {
  std::array<double, 3> c{0, 0, 0};
  for (int i = 0; i < dimension(); ++i) {
    const std::size_t n = axes_[i].vertices.size();
    c[i] = axes_[i].vertices[v % n];
    v /= n;
  }
  return position(c);
}

Eigen::Vector3d Discretizer::sample(const std::array<double, 3>& u) const {
  std::array<double, 3> c{0, 0, 0};
  for (int i = 0; i < dimension(); ++i) {
    const GridAxis& axis = axes_[i];
    const double span = axis.wraps ? kTwoPi : axis.vertices.back() - axis.vertices.front();
    c[i] = axis.vertices.front() + u[i] * span;
  }
  return position(c);
}

nlohmann::json Discretizer::describe() const {
  nlohmann::json axes = nlohmann::json::array();
  for (const GridAxis& axis : axes_)
    axes.push_back({{"name", axis.name}, {"unit", axis.unit}, {"vertices", axis.vertices}, {"wraps", axis.wraps}});
  return {{"type", type()}, {"axes", axes}, {"vertex_count", vertexCount_}, {"cell_count", cellCount_}};
}

}  // namespace mgrl
