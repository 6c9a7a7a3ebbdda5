#pragma once
/// \file
/// The Discretizer seam (DESIGN.md sec. 4; paper sec. 4.2): an avatar-centric grid over the
/// environment state e (TargetState: the target's position in the avatar frame, +Z facing,
/// +X left, Y up, metres, and its ground velocity). Q values live on the grid's vertices and
/// are interpolated multilinearly inside a cell. Grids here are products of 1 to 3 axes, each
/// a list of vertex coordinates; an axis may wrap (an angle covering the full circle), so its
/// last vertex neighbours its first. A grid may also have a layer axis (the target's speed):
/// a coordinate no action changes, so every backup from a vertex stays in its layer and
/// learners see 3-D cells, while a decision between two layers interpolates across them.
/// A moving target that turns adds turn layers outside those: one copy of the
/// layered grid per turn rate the environment model draws, never interpolated across.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "mgrl/core/params.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

/// Where a point falls: its cell and the fractional position inside it along each axis,
/// in [0, 1]. Corner k of a cell is at the upper end of axis i where bit i of k is set.
/// On a layered grid, `cell` is the cell in the lower of the two layers around e and
/// `layerFrac` the fraction towards the upper one (0 at a layer).
struct GridCell {
  std::uint32_t cell = 0;
  std::array<float, 3> frac{0, 0, 0};
  float layerFrac = 0;
};

/// Up to 16 grid vertices and their interpolation weights (non-negative, summing to 1):
/// 2^dimension corners, twice that between two layers.
struct Stencil {
  std::array<std::uint32_t, 16> vertex;
  std::array<float, 16> weight;
  int size = 0;
};

/// What a grid axis measures of the environment state (TargetState in the avatar frame).
/// Code that needs an axis asks for its role (Discretizer::axis()), never for its name.
enum class AxisRole {
  Angle,     ///< the target's bearing, atan2(x, z), rad
  Distance,  ///< its ground distance, m (the one axis of a 1-D grid: straight ahead)
  Height,    ///< its height, m
  Heading,   ///< where it moves or faces, rad (polar_velocity)
  Speed,     ///< its ground speed, m/s (a layer axis)
  Opponent,  ///< a learned opponent's discrete state (a layer axis)
  Turn,      ///< how fast a moving target's path turns, rad/s (turn layers)
};

/// One axis of a product grid.
struct GridAxis {
  AxisRole role = AxisRole::Distance;
  std::vector<double> vertices;  ///< ascending coordinates
  bool wraps = false;            ///< the axis is periodic with period 2 pi (angles only)
  /// "angle", "distance", "height", "heading", "speed", "opponent", "turn": in messages and
  /// describe().
  std::string_view name() const;
  /// "rad", "m", "m/s", "state" or "rad/s".
  std::string_view unit() const;
};

/// Vertices whose value is not free but the interpolation of other vertices' values
/// (kd_tree's hanging vertices, on a coarser neighbour's face): vertex[i] takes
/// sum over k in [begin[i], begin[i + 1]) of weight[k] * value(source[k]), and every source
/// is a free vertex. Learners keep these equations after each backup so that the
/// interpolated function stays continuous; fixed grids have none.
struct HangingVertices {
  std::vector<std::uint32_t> vertex;
  std::vector<std::uint32_t> begin{0};
  std::vector<std::uint32_t> source;
  std::vector<float> weight;
  bool empty() const { return vertex.empty(); }
  std::size_t size() const { return vertex.size(); }
  /// values[vertex[i] * stride] = sum_k weight[k] values[source[k] * stride], for every i.
  template <class T>
  void apply(T* values, std::size_t stride = 1) const {
    for (std::size_t i = 0; i < vertex.size(); ++i) {
      T sum = 0;
      for (std::uint32_t k = begin[i]; k < begin[i + 1]; ++k)
        sum += static_cast<T>(weight[k]) * values[source[k] * stride];
      values[vertex[i] * stride] = sum;
    }
  }
};

/// A named array of a discretizer's own structure (kd_tree: its tree), saved in policy
/// bundles as `<behaviour>.grid.<name>.npy` so that a table can be used with the grid it
/// was trained on. Exactly one of `ints` (int32) and `reals` (float64) holds the values.
struct StructureArray {
  std::string name;
  std::vector<std::size_t> shape;
  std::vector<std::int32_t> ints;
  std::vector<double> reals;
  bool integer = true;
  /// Where it was read from, for messages (the .npy file's path); empty when made in memory.
  std::string source;
};

/// The most vertices a grid may have (its corner table and every table over it scale with it).
inline constexpr std::size_t kMaxGridVertices = 20'000'000;

class Discretizer {
 public:
  virtual ~Discretizer() = default;

  /// The registered name, e.g. "polar2d".
  virtual std::string type() const = 0;
  /// The axes, first varying fastest in the vertex numbering:
  /// vertex = i0 + n0 * (i1 + n1 * i2).
  const std::vector<GridAxis>& axes() const { return axes_; }
  /// The axis (or the layer axis, or the turn layers) with that role, null if the grid has none.
  const GridAxis* axis(AxisRole role) const;
  int dimension() const { return static_cast<int>(axes_.size()); }
  std::size_t vertexCount() const { return vertexCount_; }
  std::size_t cellCount() const { return cellCount_; }
  /// cellCount() x 2^dimension() vertex indices: corner k of cell c at [c << dimension() | k].
  const std::vector<std::uint32_t>& cellCorners() const { return corners_; }

  /// The grid coordinates of a state (one per axis, e.g. angle, distance, height).
  virtual std::array<double, 3> coordinates(const TargetState& e) const = 0;
  /// A target position with these grid coordinates (height 0 for 2-D grids).
  virtual Eigen::Vector3d position(const std::array<double, 3>& coordinates) const = 0;
  /// The state with these grid coordinates (layer coordinate aside): position() for grids
  /// over the position alone.
  virtual TargetState state(const std::array<double, 3>& coordinates) const { return position(coordinates); }

  /// The layer axis (the target's speed), or null if the grid has none.
  const GridAxis* layerAxis() const { return layers_.vertices.empty() ? nullptr : &layers_; }
  /// Vertices per layer (all of them without a layer axis); vertex v is in speed layer
  /// (v / this) % (speed layers), turn layer v / turnVertexCount().
  std::size_t layerVertexCount() const { return layerVertices_; }
  /// The layer coordinate of a state: its speed (the one coordinate a moving_target keeps),
  /// or on a grid with opponent layers the opponent's discrete state.
  double layerCoordinate(const TargetState& e) const { return opponentLayers_ ? e.opponent : e.speed; }
  /// Repeats the grid once per discrete opponent state (`learned_opponent`): layer
  /// l holds the states whose TargetState::opponent is l. Unlike speed layers these are
  /// never interpolated across (a state is exactly at one), and an action may move a state
  /// to another layer. Throws mgrl::Error if the grid already has more than one speed layer
  /// or hanging vertices, or if the layered grid would exceed kMaxGridVertices.
  void setOpponentLayers(std::size_t count);
  bool hasOpponentLayers() const { return opponentLayers_; }
  /// Repeats the (speed-layered) grid once per turn rate of a turning moving target
  /// (`rates` rad/s, ascending, as TargetMotion::turnRates lists them): turn layer k
  /// holds the states whose TargetState::turnRate is nearest rates[k]. A moving_target keeps
  /// its turn rate, so, as with speed, every backup stays in its layer; unlike speed, a state
  /// is never between two turn layers (a model draws only these rates). Throws mgrl::Error
  /// for rates not finite and ascending, on a grid with opponent layers or hanging
  /// vertices, or past kMaxGridVertices.
  void setTurnLayers(std::vector<double> rates);
  /// The turn layers (role Turn), or null if the grid has none.
  const GridAxis* turnAxis() const { return turns_.vertices.empty() ? nullptr : &turns_; }
  /// Vertices per turn layer (all of them without turn layers); vertex v is in turn layer v / this.
  std::size_t turnVertexCount() const { return turnVertices_; }
  /// The turn layer a state is in: the one nearest its turn rate (0 without turn layers).
  std::size_t turnLayer(double turnRate) const;

  /// Locates e: false if it lies outside the grid (future value 0 there, paper sec. 4.2).
  virtual bool locate(const TargetState& e, GridCell& out) const;
  /// The cell of the nearest grid point to e (e itself if inside).
  virtual GridCell locateClamped(const TargetState& e) const;
  bool inside(const TargetState& e) const {
    GridCell ignored;
    return locate(e, ignored);
  }
  /// Vertices and multilinear weights of a located point.
  Stencil stencil(const GridCell& cell) const;
  /// The state at vertex v.
  virtual TargetState vertexState(std::size_t v) const;
  /// Vertex v's coordinates on the grid's own axes (the first dimension() are set): a
  /// product grid's axis values, so that a vertex at the avatar itself (distance 0) keeps
  /// its angle axis' value where coordinates(vertexState(v)) would give atan2(0, 0).
  virtual std::array<double, 3> vertexCoordinates(std::size_t v) const;
  /// The target position at vertex v.
  Eigen::Vector3d vertexPosition(std::size_t v) const { return vertexState(v).position; }
  /// A state uniform in grid coordinates, from u uniform in [0, 1)^4; on a layered grid
  /// u[3] picks a layer (exactly at a layer vertex: what learners restart from), with turn
  /// layers one of speed layers x turn layers.
  TargetState sample(const std::array<double, 4>& u) const;
  /// sample() from `rng`: three numbers, and a fourth only on a layered grid (so grids
  /// without layers keep the paper's random stream and tables). Learners' restarts.
  TargetState sample(Rng& rng) const;

  /// {"type", "axes": [{"name", "unit", "vertices": [...], "wraps"}], "vertex_count", "cell_count"}.
  virtual nlohmann::json describe() const;

  /// Vertices whose values are tied to others' (see HangingVertices); none for fixed grids.
  const HangingVertices& hanging() const { return hanging_; }

  // Adaptive resolution (Munos & Moore 2002). Fixed grids keep these defaults.

  /// True if refined() can split cells.
  virtual bool refinable() const { return false; }
  /// True if cell c may still be split (below the discretizer's depth limit).
  virtual bool splittable(std::uint32_t) const { return false; }
  /// The target position at the centre of cell c (grid coordinates halfway along each axis).
  virtual Eigen::Vector3d cellCentre(std::uint32_t cell) const;
  /// A copy with each listed cell split in two (cells not splittable() are skipped); its
  /// cells and vertices are numbered afresh. Throws mgrl::Error for fixed grids.
  virtual std::unique_ptr<Discretizer> refined(const std::vector<std::uint32_t>& cells) const;
  /// The initial cells along each axis that refinement started from (kd_tree); empty for
  /// fixed grids.
  virtual std::vector<long long> initialCells() const { return {}; }
  /// A copy that starts from `cells` initial cells along each axis, with this one's other
  /// parameters and unrefined (adaptive_value_iteration's `starts`). Throws mgrl::Error for
  /// fixed grids and for cells this discretizer cannot start from.
  virtual std::unique_ptr<Discretizer> withInitialCells(const std::vector<long long>& cells) const;
  /// The arrays that describe this discretizer beyond its YAML parameters (empty for fixed
  /// grids, whose parameters say everything).
  virtual std::vector<StructureArray> structure() const { return {}; }
  /// A discretizer with this one's parameters and the structure `arrays` (as structure()
  /// returned them). Throws mgrl::Error naming the array's source on any inconsistency.
  virtual std::unique_ptr<Discretizer> restored(const std::vector<StructureArray>& arrays) const;

 protected:
  /// Called by a derived constructor once its axes are known: checks them (at least 2
  /// vertices each, ascending, wrapping axes span less than 2 pi) and builds the cell table.
  void setAxes(std::vector<GridAxis> axes);
  /// For discretizers whose cells are not a product grid (kd_tree), after setAxes() with the
  /// bounding axes: the vertex and cell counts, the corner table (cellCount x 2^dimension)
  /// and the hanging vertices.
  void setCells(std::size_t vertexCount, std::size_t cellCount, std::vector<std::uint32_t> corners,
                HangingVertices hanging);
  /// After setAxes(): repeats the grid once per vertex of `layer` (ascending, not
  /// wrapping); vertex v3 of layer l becomes v3 + l * (vertices per layer), and likewise cells.
  void setLayers(GridAxis layer);

 private:
  std::vector<GridAxis> axes_;
  std::size_t vertexCount_ = 0, cellCount_ = 0;
  std::vector<std::uint32_t> corners_;
  HangingVertices hanging_;
  std::array<std::size_t, 3> cellsPerAxis_{1, 1, 1};
  /// Evenly spaced axes are located by arithmetic instead of a search: 1 / spacing, or 0.
  std::array<double, 3> inverseStep_{0, 0, 0};
  GridAxis layers_;
  bool opponentLayers_ = false;
  std::size_t layerVertices_ = 0, layerCells_ = 0;
  GridAxis turns_{AxisRole::Turn, {}, false};
  std::size_t turnVertices_ = 0, turnCells_ = 0;
  /// The layer below coordinate c and the fraction towards the next (0 at a layer, and at the
  /// last layer itself); false outside (or NaN).
  bool locateLayer(double c, std::uint32_t& layer, float& frac) const;
};

/// Multilinear weights of the 2^dimension corners for fractions `frac`.
inline void cornerWeights(int dimension, const std::array<float, 3>& frac, float* weight) {
  const int corners = 1 << dimension;
  for (int k = 0; k < corners; ++k) {
    float w = 1;
    for (int i = 0; i < dimension; ++i) w *= (k >> i & 1) ? frac[i] : 1 - frac[i];
    weight[k] = w;
  }
}

/// Factories get the model so that bounds can come from its effective hitting points.
using DiscretizerRegistry = Registry<Discretizer, const StateActionModel&>;

}  // namespace mgrl
