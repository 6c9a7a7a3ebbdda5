#include "mgrl/learning/discretizer.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

namespace {

// Each AxisRole's name and unit, in the enum's order.
constexpr std::string_view kAxisNames[][2] = {{"angle", "rad"},   {"distance", "m"}, {"height", "m"},
                                              {"heading", "rad"}, {"speed", "m/s"},  {"opponent", "state"},
                                              {"turn", "rad/s"}};

}  // namespace

std::string_view GridAxis::name() const { return kAxisNames[static_cast<int>(role)][0]; }

std::string_view GridAxis::unit() const { return kAxisNames[static_cast<int>(role)][1]; }

const GridAxis* Discretizer::axis(AxisRole role) const {
  for (const GridAxis& a : axes_)
    if (a.role == role) return &a;
  if (layers_.role == role && !layers_.vertices.empty()) return &layers_;
  return turns_.role == role && !turns_.vertices.empty() ? &turns_ : nullptr;
}

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
      throw Error(
          fmt::format("{}: {}: expected at least 2 vertices, found {}", type(), axis.name(), axis.vertices.size()));
    for (std::size_t k = 0; k < axis.vertices.size(); ++k) {
      if (!std::isfinite(axis.vertices[k]))
        throw Error(fmt::format("{}: {}: expected finite vertex coordinates", type(), axis.name()));
      if (k > 0 && !(axis.vertices[k] > axis.vertices[k - 1]))
        throw Error(fmt::format("{}: {}: expected ascending vertex coordinates, found {} after {}", type(), axis.name(),
                                axis.vertices[k], axis.vertices[k - 1]));
    }
    if (axis.wraps && !(axis.vertices.back() - axis.vertices.front() < kTwoPi))
      throw Error(fmt::format("{}: {}: a wrapping axis must span less than 360 degrees", type(), axis.name()));
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
  // The size is checked before the corner table is made (a 10000 x 10000 polar
  // grid spent 30 s and 3 GB before anything said no).
  if (vertexCount_ > kMaxGridVertices) {
    std::vector<std::string> sizes;
    for (const GridAxis& axis : axes) sizes.push_back(fmt::format("{} {}", axis.vertices.size(), axis.name()));
    throw Error(fmt::format("{}: expected a grid of at most {} vertices, found {} ({})", type(), kMaxGridVertices,
                            vertexCount_, fmt::join(sizes, " x ")));
  }
  axes_ = std::move(axes);
  layerVertices_ = turnVertices_ = vertexCount_;
  layerCells_ = turnCells_ = cellCount_;
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
  layerVertices_ = turnVertices_ = vertexCount;
  layerCells_ = turnCells_ = cellCount;
  corners_ = std::move(corners);
  hanging_ = std::move(hanging);
}

void Discretizer::setLayers(GridAxis layer) {
  if (layer.vertices.empty() || layer.wraps)
    throw Error(fmt::format("{}: {}: expected at least 1 layer and no wrap", type(), layer.name()));
  for (std::size_t k = 0; k < layer.vertices.size(); ++k) {
    if (!std::isfinite(layer.vertices[k]) || (k > 0 && !(layer.vertices[k] > layer.vertices[k - 1])))
      throw Error(fmt::format("{}: {}: expected finite ascending layer coordinates", type(), layer.name()));
  }
  const std::size_t count = layer.vertices.size();
  if (!hanging_.empty()) throw Error(fmt::format("{}: a grid with hanging vertices cannot have layers", type()));
  if (!turns_.vertices.empty())
    throw Error(fmt::format("{}: {} layers cannot be added after turn layers", type(), layer.name()));
  if (refinable())
    throw Error(fmt::format("{}: an adaptive grid cannot hold {} layers; use polar_velocity", type(), layer.name()));
  if (layerVertices_ * count > kMaxGridVertices)
    throw Error(fmt::format("{}: expected a grid of at most {} vertices, found {} ({} per layer x {} {})", type(),
                            kMaxGridVertices, layerVertices_ * count, layerVertices_, count, layer.name()));
  const std::size_t perCell = std::size_t{1} << dimension();
  std::vector<std::uint32_t> corners(layerCells_ * count * perCell);
  for (std::size_t l = 0; l < count; ++l)
    for (std::size_t k = 0; k < layerCells_ * perCell; ++k)
      corners[l * layerCells_ * perCell + k] = static_cast<std::uint32_t>(corners_[k] + l * layerVertices_);
  corners_ = std::move(corners);
  vertexCount_ = turnVertices_ = layerVertices_ * count;
  cellCount_ = turnCells_ = layerCells_ * count;
  layers_ = std::move(layer);
}

void Discretizer::setTurnLayers(std::vector<double> rates) {
  if (rates.empty()) throw Error(fmt::format("{}: expected at least 1 turn rate, found none", type()));
  for (std::size_t k = 0; k < rates.size(); ++k)
    if (!std::isfinite(rates[k]) || (k > 0 && !(rates[k] > rates[k - 1])))
      throw Error(fmt::format("{}: expected finite ascending turn rates, found {} at {}", type(), rates[k], k));
  if (!turns_.vertices.empty()) throw Error(fmt::format("{}: the grid has turn layers already", type()));
  if (opponentLayers_) throw Error(fmt::format("{}: a grid with a learned opponent's layers cannot turn", type()));
  if (refinable()) throw Error(fmt::format("{}: an adaptive grid cannot hold turn layers; use polar_velocity", type()));
  if (!hanging_.empty()) throw Error(fmt::format("{}: a grid with hanging vertices cannot have layers", type()));
  const std::size_t count = rates.size();
  if (vertexCount_ * count > kMaxGridVertices)
    throw Error(fmt::format("{}: expected a grid of at most {} vertices, found {} ({} per turn layer x {} turn rates)",
                            type(), kMaxGridVertices, vertexCount_ * count, vertexCount_, count));
  const std::size_t perBlock = corners_.size();
  std::vector<std::uint32_t> corners(perBlock * count);
  for (std::size_t l = 0; l < count; ++l)
    for (std::size_t k = 0; k < perBlock; ++k)
      corners[l * perBlock + k] = static_cast<std::uint32_t>(corners_[k] + l * vertexCount_);
  corners_ = std::move(corners);
  turnVertices_ = vertexCount_;
  turnCells_ = cellCount_;
  vertexCount_ *= count;
  cellCount_ *= count;
  turns_.vertices = std::move(rates);
}

std::size_t Discretizer::turnLayer(double turnRate) const {
  const std::vector<double>& v = turns_.vertices;
  if (v.size() < 2) return 0;
  // The first rate past the midpoint to the next one: the nearest (ties go down).
  std::size_t k = 0;
  while (k + 1 < v.size() && turnRate > 0.5 * (v[k] + v[k + 1])) ++k;
  return k;
}

void Discretizer::setOpponentLayers(std::size_t count) {
  if (opponentLayers_) throw Error(fmt::format("{}: the grid has opponent layers already", type()));
  if (layers_.vertices.size() > 1)
    throw Error(fmt::format("{}: expected one speed layer under a learned opponent's layers, found {} (set speeds: 1)",
                            type(), layers_.vertices.size()));
  if (count == 0 || count > kMaxGridVertices)
    throw Error(fmt::format("{}: expected 1 to {} opponent states, found {}", type(), kMaxGridVertices, count));
  std::vector<double> layers(count);
  for (std::size_t l = 0; l < count; ++l) layers[l] = static_cast<double>(l);
  setLayers(GridAxis{AxisRole::Opponent, std::move(layers), false});
  opponentLayers_ = true;
}

bool Discretizer::locateLayer(double c, std::uint32_t& layer, float& frac) const {
  const std::vector<double>& v = layers_.vertices;
  const std::size_t n = v.size();
  if (!(c >= v[0] && c <= v[n - 1])) return false;
  // The last vertex at or below c: a state exactly at a layer (every vertex, and every
  // state a backup moves one to) is in that layer with fraction 0, the top one included.
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(v.begin(), v.end(), c) - v.begin()) - 1;
  layer = static_cast<std::uint32_t>(i);
  frac = i + 1 < n ? static_cast<float>(std::clamp((c - v[i]) / (v[i + 1] - v[i]), 0.0, 1.0)) : 0.0f;
  return true;
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

bool Discretizer::locate(const TargetState& e, GridCell& out) const {
  const std::array<double, 3> c = coordinates(e);
  std::size_t cell = 0, stride = 1;
  for (int i = 0; i < dimension(); ++i) {
    std::uint32_t index = 0;
    if (!locateOnAxis(axes_[i], inverseStep_[i], c[i], index, out.frac[i])) return false;
    cell += index * stride;
    stride *= cellsPerAxis_[i];
  }
  if (!layers_.vertices.empty()) {
    std::uint32_t layer = 0;
    if (!locateLayer(layerCoordinate(e), layer, out.layerFrac)) return false;
    cell += layer * layerCells_;
  }
  if (!turns_.vertices.empty()) {
    if (std::isnan(e.turnRate)) return false;
    cell += turnLayer(e.turnRate) * turnCells_;
  }
  out.cell = static_cast<std::uint32_t>(cell);
  return true;
}

GridCell Discretizer::locateClamped(const TargetState& e) const {
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
  if (!layers_.vertices.empty()) {
    const double l = layerCoordinate(e);
    std::uint32_t layer = 0;
    locateLayer(std::clamp(std::isnan(l) ? layers_.vertices.front() : l, layers_.vertices.front(),
                           layers_.vertices.back()),
                layer, out.layerFrac);
    cell += layer * layerCells_;
  }
  if (!turns_.vertices.empty()) cell += turnLayer(std::isnan(e.turnRate) ? 0.0 : e.turnRate) * turnCells_;
  out.cell = static_cast<std::uint32_t>(cell);
  return out;
}

Stencil Discretizer::stencil(const GridCell& cell) const {
  Stencil s;
  const int d = dimension();
  const int corners = 1 << d;
  cornerWeights(d, cell.frac, s.weight.data());
  for (int k = 0; k < corners; ++k) s.vertex[k] = corners_[(static_cast<std::size_t>(cell.cell) << d) | k];
  s.size = corners;
  if (cell.layerFrac > 0) {
    // Between two layers: the same corners one layer up, weighted by the layer fraction.
    const float up = cell.layerFrac, down = 1 - up;
    for (int k = 0; k < corners; ++k) {
      s.vertex[corners + k] = s.vertex[k] + static_cast<std::uint32_t>(layerVertices_);
      s.weight[corners + k] = s.weight[k] * up;
      s.weight[k] *= down;
    }
    s.size = 2 * corners;
  }
  return s;
}

std::array<double, 3> Discretizer::vertexCoordinates(std::size_t v) const {
  std::array<double, 3> c{0, 0, 0};
  v %= turnVertices_;  // the axes repeat in every turn and speed layer
  v %= layerVertices_;
  for (int i = 0; i < dimension(); ++i) {
    const std::size_t n = axes_[i].vertices.size();
    c[i] = axes_[i].vertices[v % n];
    v /= n;
  }
  return c;
}

TargetState Discretizer::vertexState(std::size_t v) const {
  const std::size_t turn = v / turnVertices_;
  const std::size_t layer = (v % turnVertices_) / layerVertices_;
  TargetState e = state(Discretizer::vertexCoordinates(v));
  if (opponentLayers_)
    e.opponent = static_cast<std::int32_t>(layer);
  else if (!layers_.vertices.empty())
    e.speed = layers_.vertices[layer];
  if (!turns_.vertices.empty()) e.turnRate = turns_.vertices[turn];
  return e;
}

TargetState Discretizer::sample(const std::array<double, 4>& u) const {
  std::array<double, 3> c{0, 0, 0};
  for (int i = 0; i < dimension(); ++i) {
    const GridAxis& axis = axes_[i];
    const double span = axis.wraps ? kTwoPi : axis.vertices.back() - axis.vertices.front();
    c[i] = axis.vertices.front() + u[i] * span;
  }
  TargetState e = state(c);
  const std::size_t speeds = std::max<std::size_t>(1, layers_.vertices.size());
  const std::size_t n = speeds * std::max<std::size_t>(1, turns_.vertices.size());
  const std::size_t pick = std::min(n - 1, static_cast<std::size_t>(u[3] * static_cast<double>(n)));
  if (!layers_.vertices.empty()) {
    const std::size_t layer = pick % speeds;
    if (opponentLayers_)
      e.opponent = static_cast<std::int32_t>(layer);
    else
      e.speed = layers_.vertices[layer];
  }
  if (!turns_.vertices.empty()) e.turnRate = turns_.vertices[pick / speeds];
  return e;
}

TargetState Discretizer::sample(Rng& rng) const {
  const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
  return sample({u0, u1, u2, layers_.vertices.empty() && turns_.vertices.empty() ? 0.0 : rng.uniform()});
}

nlohmann::json Discretizer::describe() const {
  nlohmann::json axes = nlohmann::json::array();
  for (const GridAxis& axis : axes_)
    axes.push_back({{"name", std::string(axis.name())},
                    {"unit", std::string(axis.unit())},
                    {"vertices", axis.vertices},
                    {"wraps", axis.wraps}});
  nlohmann::json out = {{"type", type()}, {"axes", axes}, {"vertex_count", vertexCount_}, {"cell_count", cellCount_}};
  if (!layers_.vertices.empty())
    out["layers"] = {
        {"name", std::string(layers_.name())}, {"unit", std::string(layers_.unit())}, {"vertices", layers_.vertices}};
  if (!turns_.vertices.empty())
    out["turn_layers"] = {
        {"name", std::string(turns_.name())}, {"unit", std::string(turns_.unit())}, {"vertices", turns_.vertices}};
  return out;
}

}  // namespace mgrl
