#pragma once
/// \file
/// kd_tree's class, private to this folder: an adaptive grid over the same avatar-frame
/// coordinates as polar2d and cylindrical3d (Munos & Moore 2002's kd-trie). Leaves
/// are boxes, values live at their corners, and a point is interpolated multilinearly from
/// the corners of its leaf. Nothing outside discretizers/ includes this header: the rest of
/// the program reaches the tree through the Discretizer seam and registerKdTree().
///
/// Continuity. A corner of a fine leaf that lies inside a face (or edge) of a coarser
/// neighbour is a hanging vertex: its value is not free but the coarse leaf's interpolation
/// at that point (HangingVertices), expanded down to free vertices. The fine side then
/// interpolates a multilinear function restricted to a sub-box, which it reproduces
/// exactly, so the two sides agree on the face. For that argument to hold in 3-D the face a
/// fine leaf shares with a coarse one must be a face of the fine leaf; splitting every cell
/// at its midpoint along an axis fixed by its depth (the same sequence for the whole tree)
/// guarantees it: the leaves at depth k are cells of one uniform grid G_k, and G_k refines
/// every G_j, j < k. (With a free choice of axis per cell two leaves can meet on a rectangle
/// whose corners belong to neither, and no vertex equation makes them agree.)
///
/// Any number of initial cells. n cells along an axis are r = n / 2^p root boxes (r odd)
/// split p times: the tree is a forest whose roots are the cells of a uniform r_0 x r_1 x r_2
/// grid G_0, each root split by the same depth sequence. The leaves at depth k are still
/// cells of one uniform grid (r_i 2^(halvings of axis i by depth k) cells along axis i), and
/// G_k still refines every G_j, so the argument above holds unchanged. Power-of-two counts
/// give one root: the tree and its bundle arrays are what they were before roots existed.
///
/// The parts, one file each, share the node arrays below and keep that invariant together:
///   kd_tree.cpp        the parameters: the split sequence, the initial tree, registration;
///   kd_tree_build.cpp  splitting, the leaves, vertices and hanging vertices (rebuild), and
///                      refinement (refined, conforming splits);
///   kd_tree_locate.cpp the runtime side: a point's leaf and its weights, vertex positions;
///   kd_tree_io.cpp     the tree as arrays for the policy bundle, and restored from them.
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "discretizers.hpp"

namespace mgrl::discretizers {

class KdTree final : public Discretizer {
 public:
  /// A point in integer grid coordinates (units of the finest possible cell), per axis.
  using Key = std::array<std::uint64_t, 3>;

  /// The tree the parameters `p` describe (kd_tree's ParamSpecs) for model `m`; throws the
  /// parameters' ConfigError for initial cells or a max_depth the tree cannot have.
  KdTree(const Params& p, const StateActionModel& m);

  /// The tree over bounds `b` starting from `initial` cells (angle, distance, height; the
  /// parameters' unless adaptive_value_iteration tries other starts).
  KdTree(const Params& p, const Bounds& b, const std::array<long long, 3>& initial);

  std::string type() const override { return "kd_tree"; }

  std::array<double, 3> coordinates(const TargetState& state) const override;
  Eigen::Vector3d position(const std::array<double, 3>& c) const override;
  bool locate(const TargetState& e, GridCell& out) const override;
  GridCell locateClamped(const TargetState& e) const override;
  TargetState vertexState(std::size_t v) const override;
  /// A tree's vertices lie on no product of axes: their coordinates are their states'.
  std::array<double, 3> vertexCoordinates(std::size_t v) const override { return coordinates(vertexState(v)); }

  nlohmann::json describe() const override;

  bool refinable() const override { return true; }
  bool splittable(std::uint32_t cell) const override {
    return cell < leafNode_.size() && nodeDepth(static_cast<std::size_t>(leafNode_[cell])) < maxDepth_;
  }
  Eigen::Vector3d cellCentre(std::uint32_t cell) const override;
  std::unique_ptr<Discretizer> refined(const std::vector<std::uint32_t>& cells) const override;

  std::vector<StructureArray> structure() const override;
  std::vector<long long> initialCells() const override { return axisOrder(initial_); }
  std::unique_ptr<Discretizer> withInitialCells(const std::vector<long long>& cells) const override;
  std::unique_ptr<Discretizer> restored(const std::vector<StructureArray>& arrays) const override;

 private:
  static constexpr double kTwoPi = 2 * M_PI;
  static constexpr int kMaxAxisSplits = 30;  // integer corner coordinates fit in 32 bits

  // Initial cells from (angle, distance, height) to the tree's axes and back.
  std::vector<long long> axisOrder(const std::array<long long, 3>& c) const {
    if (dimension_ == 1) return {c[1]};
    if (dimension_ == 2) return {c[0], c[1]};
    return {c[0], c[1], c[2]};
  }
  std::array<long long, 3> paramOrder(const std::vector<long long>& cells) const;
  // The tree `arrays` describe, grown from this tree's initial cells (restored()).
  std::unique_ptr<Discretizer> restoredFrom(const std::vector<StructureArray>& arrays) const;

  // The axis split at `depth` and the depth of node n (by walking up from the root would
  // need parents; depth is kept per node instead).
  int nodeDepth(std::size_t n) const { return depth_.empty() ? 0 : depth_[n]; }
  double wrapped(int i, double c) const {
    if (c < lo_[i] || c >= lo_[i] + kTwoPi) {
      c = lo_[i] + std::fmod(std::fmod(c - lo_[i], kTwoPi) + kTwoPi, kTwoPi);
      if (c >= lo_[i] + kTwoPi) c = lo_[i];
    }
    return c;
  }
  // The coordinate of integer position k on axis i (units of span / (roots 2^levels)).
  double coordinate(int i, std::uint64_t k) const {
    return lo_[i] + span_[i] * (std::ldexp(static_cast<double>(k), -levels_[i]) / static_cast<double>(roots_[i]));
  }
  // Integer positions per root box along axis i.
  std::uint64_t rootKeys(int i) const { return std::uint64_t{1} << levels_[i]; }
  // The integer positions of the whole grid's far corner (on a wrapping axis, its start again).
  Key fullKey() const {
    Key full{0, 0, 0};
    for (int i = 0; i < dimension_; ++i) full[i] = roots_[i] << levels_[i];
    return full;
  }
  // The root whose box holds grid coordinates c (the upper one on a shared face, as a split does).
  // Inline, as find(), and defined beside locate() in kd_tree_locate.cpp, the only caller.
  inline std::size_t rootOf(const std::array<double, 3>& c) const;
  // The box of root r in integer positions.
  void rootBox(std::size_t r, Key& lo, Key& hi) const;
  double splitValue(std::size_t n) const { return coordinate(axis_[n], splitKey_[n]); }

  // Splits leaf node n in two at its depth's axis (new nodes at the end; rebuild() after).
  void split(std::size_t n);

  // The leaf holding grid coordinates c (inside the grid) and c's fractions in it. Inline:
  // every lookup (locate(), locateClamped()) takes this path, so it is compiled into them.
  inline GridCell find(const std::array<double, 3>& c) const;

  // Leaves, vertices and hanging vertices from the nodes (axis_, children_). `source` names
  // the tree in messages. Throws mgrl::Error for a cycle, an unreachable node or a node
  // split on another axis than its depth's.
  void rebuild(const std::string& source);
  // rebuild()'s steps: the nodes' depths, split keys and the leaves in depth-first order;
  // the vertices (leaf corners) and each leaf's corners, returning the vertices' keys;
  // the hanging vertices' equations.
  void numberLeaves(const std::string& source);
  std::vector<Key> numberVertices(std::vector<std::uint32_t>& corners);
  HangingVertices hangingVertices(const std::vector<Key>& keys, const std::vector<std::uint32_t>& corners,
                                  const std::string& source) const;

  // Leaves whose closed box holds integer point k, with their depth, into `out`.
  void containing(const Key& k, std::vector<std::int32_t>& out) const;
  // Whether integer point k is a corner of `leaf`'s box.
  bool isCorner(const Key& k, std::int32_t leaf) const {
    for (int i = 0; i < dimension_; ++i)
      if (k[i] != leafLoKey_[leaf][i] && k[i] != leafHiKey_[leaf][i]) return false;
    return true;
  }

  // Splits, level by level, every leaf that holds one of `keys` inside its box without
  // having it as a corner, until each key is a corner of every leaf around it (or those
  // leaves are at max_depth): the keys become free vertices. See `refinement`.
  void freeCorners(const std::vector<Key>& keys);

  Params params_;
  Bounds bounds_;
  std::array<long long, 3> initial_{1, 1, 1};  // initial cells (angle, distance, height)
  int dimension_ = 0, coordinates_ = 0, initialDepth_ = 0, maxDepth_ = 0;
  // Root boxes along each axis (the odd part of its initial cells) and their product; nodes
  // 0 .. rootCount_ - 1 are the roots, the first axis varying fastest.
  std::array<std::uint64_t, 3> roots_{1, 1, 1};
  std::size_t rootCount_ = 1;
  bool conforming_ = false;  // refinement: conforming
  double height_ = 0;
  std::array<double, 3> lo_{0, 0, 0}, span_{1, 1, 1};
  std::array<bool, 3> wraps_{false, false, false};
  std::array<int, 3> levels_{0, 0, 0};  // halvings of each axis down to max_depth
  std::vector<int> sequence_;           // split axis by depth
  // Nodes: split axis (-1 leaf), children (low, high; -1 for leaves), depth.
  std::vector<std::int32_t> axis_, children_;
  std::vector<int> depth_{0};
  // Derived by rebuild().
  std::vector<std::uint64_t> splitKey_;
  std::vector<double> splitCoordinate_;
  std::vector<std::int32_t> leafNode_, nodeLeaf_;
  std::vector<Key> leafLoKey_, leafHiKey_;
  std::vector<double> leafLo_, leafHi_, vertexCoordinates_;
};

}  // namespace mgrl::discretizers
