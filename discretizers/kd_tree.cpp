// kd_tree: an adaptive grid over the same avatar-frame coordinates as polar2d and
// cylindrical3d (issue 16; Munos & Moore 2002's kd-trie). Leaves are boxes, values live at
// their corners, and a point is interpolated multilinearly from the corners of its leaf.
//
// Continuity. A corner of a fine leaf that lies inside a face (or edge) of a coarser
// neighbour is a hanging vertex: its value is not free but the coarse leaf's interpolation
// at that point (HangingVertices), expanded down to free vertices. The fine side then
// interpolates a multilinear function restricted to a sub-box, which it reproduces
// exactly, so the two sides agree on the face. For that argument to hold in 3-D the face a
// fine leaf shares with a coarse one must be a face of the fine leaf; splitting every cell
// at its midpoint along an axis fixed by its depth (the same sequence for the whole tree)
// guarantees it: the leaves at depth k are cells of one uniform grid G_k, and G_k refines
// every G_j, j < k. (With a free choice of axis per cell two leaves can meet on a rectangle
// whose corners belong to neither, and no vertex equation makes them agree.)
//
// Any number of initial cells. n cells along an axis are r = n / 2^p root boxes (r odd)
// split p times: the tree is a forest whose roots are the cells of a uniform r_0 x r_1 x r_2
// grid G_0, each root split by the same depth sequence. The leaves at depth k are still
// cells of one uniform grid (r_i 2^(halvings of axis i by depth k) cells along axis i), and
// G_k still refines every G_j, so the argument above holds unchanged. Power-of-two counts
// give one root: the tree and its bundle arrays are what they were before roots existed.
//
// Why one file of about 800 lines: the tree's split sequence, its locate, its hanging
// vertices and its rebuild keep one invariant together (the two sides of every face agree),
// on node arrays nothing else reads; apart, they would share those arrays through a header
// that only this plug-in uses.
#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "discretizers.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl::discretizers {

namespace {

constexpr double kTwoPi = 2 * M_PI;
constexpr int kMaxAxisSplits = 30;  // integer corner coordinates fit in 32 bits

using Key = std::array<std::uint64_t, 3>;

class KdTree final : public Discretizer {
 public:
  KdTree(const Params& p, const StateActionModel& m)
      : KdTree(p, chosenBounds(p, m, p.choice("coordinates") == "cylindrical"),
               {p.integer("angle_cells"), p.integer("distance_cells"), p.integer("height_cells")}) {}

  // The tree over bounds `b` starting from `initial` cells (angle, distance, height; the
  // parameters' unless adaptive_value_iteration tries other starts).
  KdTree(const Params& p, const Bounds& b, const std::array<long long, 3>& initial)
      : params_(p), bounds_(b), initial_(initial) {
    const std::string& kind = p.choice("coordinates");
    dimension_ = kind == "distance" ? 1 : kind == "polar" ? 2 : 3;
    coordinates_ = dimension_;
    height_ = p.number("height");
    // Axes in the order of polar2d / cylindrical3d; the 1-D tree is the distance straight ahead.
    std::vector<GridAxis> axes;
    std::array<long long, 3> cells{1, 1, 1};  // the power-of-two part of each axis's cells
    const long long angleCells = initial[0], distanceCells = initial[1], heightCells = initial[2];
    auto add = [&](AxisRole role, double lo, double hi, bool wraps, long long n, std::string_view key) {
      if (n <= 0) p.fail(key, fmt::format("expected at least 1 cell, found {}", n));
      const int i = static_cast<int>(axes.size());
      lo_[i] = lo;
      span_[i] = wraps ? kTwoPi : hi - lo;
      wraps_[i] = wraps;
      cells[i] = n & -n;  // the largest power of two dividing n
      roots_[i] = static_cast<std::uint64_t>(n / cells[i]);
      // A wrapping axis is shown by its start and half a turn (setAxes needs a span < 2 pi).
      axes.push_back(GridAxis{role, {lo, wraps ? lo + M_PI : hi}, wraps});
    };
    if (dimension_ == 1) {
      add(AxisRole::Distance, b.distance[0], b.distance[1], false, distanceCells, "distance_cells");
    } else {
      const bool wrap = b.angle[1] - b.angle[0] >= kTwoPi - 1e-9;
      add(AxisRole::Angle, b.angle[0], wrap ? b.angle[0] + kTwoPi : b.angle[1], wrap, angleCells, "angle_cells");
      add(AxisRole::Distance, b.distance[0], b.distance[1], false, distanceCells, "distance_cells");
      if (dimension_ == 3) add(AxisRole::Height, b.height[0], b.height[1], false, heightCells, "height_cells");
    }
    // Issue 19: the initial tree's vertices are checked before any node is made.
    double initialVertices = 1;
    for (int i = 0; i < dimension_; ++i)
      initialVertices *= static_cast<double>(roots_[i] * cells[i]) + (wraps_[i] ? 0 : 1);
    if (initialVertices > static_cast<double>(kMaxGridVertices))
      p.fail(dimension_ == 1 ? "distance_cells" : "angle_cells",
             fmt::format("expected initial cells ({}) with at most {} vertices, found {} vertices",
                         dimension_ == 1 ? "distance" : dimension_ == 2 ? "angle x distance" : "angle x distance x height",
                         kMaxGridVertices, initialVertices));
    rootCount_ = static_cast<std::size_t>(roots_[0] * roots_[1] * roots_[2]);
    // The split sequence: first the initial cells, round robin over the axes that still
    // need splits, then round robin over every axis.
    std::array<int, 3> remaining{0, 0, 0};
    for (int i = 0; i < dimension_; ++i)
      while ((1LL << remaining[i]) < cells[i]) ++remaining[i];
    initialDepth_ = remaining[0] + remaining[1] + remaining[2];
    maxDepth_ = static_cast<int>(p.integer("max_depth"));
    conforming_ = p.choice("refinement") == "conforming";
    if (maxDepth_ < initialDepth_)
      p.fail("max_depth", fmt::format("expected at least the {} splits of the initial cells, found {}", initialDepth_,
                                      maxDepth_));
    for (int i = 0; dimension_ > 0 && std::any_of(remaining.begin(), remaining.end(), [](int r) { return r > 0; });
         i = (i + 1) % dimension_)
      if (remaining[i] > 0) {
        sequence_.push_back(i);
        --remaining[i];
      }
    if (p.choice("split_axes") == "longest") {
      // Each further depth halves the axis whose cells are then longest in metres (an angle
      // as the arc at the middle distance), ties to the first axis: resolution goes where the
      // volume is long instead of evenly to every axis. Still one axis per depth, so the
      // continuity argument above holds.
      std::array<double, 3> length{0, 0, 0};
      const double radius = dimension_ > 1 ? std::max(0.5 * (b.distance[0] + b.distance[1]), 0.1) : 1.0;
      for (int i = 0; i < dimension_; ++i) {
        int halvings = 0;
        for (int axis : sequence_) halvings += axis == i ? 1 : 0;
        length[i] = std::ldexp(span_[i] * (i == 0 && dimension_ > 1 ? radius : 1.0), -halvings) /
                    static_cast<double>(roots_[i]);
      }
      while (static_cast<int>(sequence_.size()) < maxDepth_) {
        int longest = 0;
        for (int i = 1; i < dimension_; ++i)
          if (length[i] > length[longest] * (1 + 1e-9)) longest = i;
        sequence_.push_back(longest);
        length[longest] /= 2;
      }
    }
    for (int i = 0; static_cast<int>(sequence_.size()) < maxDepth_; i = (i + 1) % dimension_) sequence_.push_back(i);
    for (int axis : sequence_) ++levels_[axis];
    for (int i = 0; i < dimension_; ++i)
      if (levels_[i] > kMaxAxisSplits)
        p.fail("max_depth", fmt::format("expected at most {} halvings of the {} axis, found {}; lower max_depth",
                                        kMaxAxisSplits, axes[i].name(), levels_[i]));
    setAxes(std::move(axes));
    // The initial tree: the roots, every leaf split down to the initial depth.
    axis_.assign(rootCount_, -1);
    children_.assign(2 * rootCount_, -1);
    depth_.assign(rootCount_, 0);
    for (int depth = 0; depth < initialDepth_; ++depth) {
      const std::size_t nodes = axis_.size();
      for (std::size_t n = 0; n < nodes; ++n)
        if (axis_[n] < 0 && nodeDepth(n) == depth) split(n);
    }
    rebuild("kd_tree");
  }

  std::string type() const override { return "kd_tree"; }

  std::array<double, 3> coordinates(const TargetState& state) const override {
    const Eigen::Vector3d& e = state.position;
    const double angle = std::atan2(e.x(), e.z()), distance = std::hypot(e.x(), e.z());
    if (coordinates_ == 1) return {std::copysign(distance, e.z()), 0, 0};
    return {angle, distance, coordinates_ == 3 ? e.y() : 0.0};
  }
  Eigen::Vector3d position(const std::array<double, 3>& c) const override {
    if (coordinates_ == 1) return {0, height_, c[0]};
    return {c[1] * std::sin(c[0]), coordinates_ == 3 ? c[2] : height_, c[1] * std::cos(c[0])};
  }

  bool locate(const TargetState& e, GridCell& out) const override {
    std::array<double, 3> c = coordinates(e);
    for (int i = 0; i < dimension_; ++i) {
      if (!std::isfinite(c[i])) return false;
      if (wraps_[i]) c[i] = wrapped(i, c[i]);
      else if (!(c[i] >= lo_[i] && c[i] <= lo_[i] + span_[i])) return false;
    }
    out = find(c);
    return true;
  }

  GridCell locateClamped(const TargetState& e) const override {
    std::array<double, 3> c = coordinates(e);
    for (int i = 0; i < dimension_; ++i) {
      if (std::isnan(c[i])) c[i] = lo_[i];
      c[i] = wraps_[i] ? wrapped(i, c[i]) : std::clamp(c[i], lo_[i], lo_[i] + span_[i]);
    }
    return find(c);
  }

  TargetState vertexState(std::size_t v) const override {
    std::array<double, 3> c{0, 0, 0};
    for (int i = 0; i < dimension_; ++i) c[i] = vertexCoordinates_[v * dimension_ + i];
    return position(c);
  }

  nlohmann::json describe() const override {
    nlohmann::json d = Discretizer::describe();
    nlohmann::json bounds = nlohmann::json::array();
    for (int i = 0; i < dimension_; ++i) bounds.push_back({lo_[i], lo_[i] + span_[i]});
    int deepest = 0;
    for (std::int32_t node : leafNode_) deepest = std::max(deepest, nodeDepth(static_cast<std::size_t>(node)));
    d["bounds"] = bounds;
    d["node_count"] = axis_.size();
    d["leaf_count"] = leafNode_.size();
    d["hanging_vertex_count"] = hanging().size();
    d["deepest_leaf"] = deepest;
    d["initial_depth"] = initialDepth_;
    d["initial_cells"] = initialCells();
    d["root_cells"] = std::vector<std::uint64_t>(roots_.begin(), roots_.begin() + dimension_);
    d["max_depth"] = maxDepth_;
    return d;
  }

  bool refinable() const override { return true; }
  bool splittable(std::uint32_t cell) const override {
    return cell < leafNode_.size() && nodeDepth(static_cast<std::size_t>(leafNode_[cell])) < maxDepth_;
  }
  Eigen::Vector3d cellCentre(std::uint32_t cell) const override {
    std::array<double, 3> c{0, 0, 0};
    for (int i = 0; i < dimension_; ++i) c[i] = 0.5 * (leafLo_[3 * cell + i] + leafHi_[3 * cell + i]);
    return position(c);
  }

  std::unique_ptr<Discretizer> refined(const std::vector<std::uint32_t>& cells) const override {
    auto copy = std::make_unique<KdTree>(*this);
    std::vector<std::uint32_t> sorted(cells);
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    std::vector<Key> faceCorners;  // the corners of the new faces
    for (std::uint32_t cell : sorted) {
      if (!splittable(cell)) continue;
      const auto node = static_cast<std::size_t>(leafNode_[cell]);
      const int axis = sequence_[static_cast<std::size_t>(nodeDepth(node))];
      for (std::size_t k = 0; k < (std::size_t{1} << dimension_); ++k) {
        if (k >> axis & 1) continue;
        Key key{0, 0, 0};
        for (int i = 0; i < dimension_; ++i)
          key[i] = i == axis ? (leafLoKey_[cell][i] + leafHiKey_[cell][i]) / 2
                             : (k >> i & 1) ? leafHiKey_[cell][i] : leafLoKey_[cell][i];
        faceCorners.push_back(key);
      }
      copy->split(node);
    }
    copy->rebuild("kd_tree");
    if (conforming_) copy->freeCorners(faceCorners);
    return copy;
  }

  std::vector<StructureArray> structure() const override {
    const std::size_t nodes = axis_.size(), leaves = leafNode_.size(), corners = std::size_t{1} << dimension_;
    std::vector<StructureArray> out;
    StructureArray axis{"split_axis", {nodes}, axis_, {}, true, {}};
    StructureArray value{"split_value", {nodes}, {}, std::vector<double>(nodes, NAN), false, {}};
    for (std::size_t n = 0; n < nodes; ++n)
      if (axis_[n] >= 0) value.reals[n] = splitValue(n);
    StructureArray children{"children", {nodes, 2}, children_, {}, true, {}};
    StructureArray leafCorners{"leaf_corners", {leaves, corners}, {}, {}, true, {}};
    for (std::uint32_t v : cellCorners()) leafCorners.ints.push_back(static_cast<std::int32_t>(v));
    StructureArray bounds{"bounds", {static_cast<std::size_t>(dimension_), 2}, {}, {}, false, {}};
    for (int i = 0; i < dimension_; ++i) bounds.reals.insert(bounds.reals.end(), {lo_[i], lo_[i] + span_[i]});
    StructureArray coordinates{"vertex_coordinates", {vertexCount(), static_cast<std::size_t>(dimension_)},
                               {}, vertexCoordinates_, false, {}};
    out.push_back(std::move(axis));
    out.push_back(std::move(value));
    out.push_back(std::move(children));
    out.push_back(std::move(leafCorners));
    out.push_back(std::move(bounds));
    out.push_back(std::move(coordinates));
    const std::array<long long, 3> given{params_.integer("angle_cells"), params_.integer("distance_cells"),
                                         params_.integer("height_cells")};
    if (axisOrder(initial_) != axisOrder(given)) {
      // Written only when adaptive_value_iteration started elsewhere than the parameters say.
      StructureArray start{"start_cells", {static_cast<std::size_t>(dimension_)}, {}, {}, true, {}};
      for (long long n : axisOrder(initial_)) start.ints.push_back(static_cast<std::int32_t>(n));
      out.push_back(std::move(start));
    }
    if (rootCount_ > 1) {
      // Written only for a forest, so that one-root trees keep the arrays they always had.
      StructureArray roots{"roots", {static_cast<std::size_t>(dimension_)}, {}, {}, true, {}};
      for (int i = 0; i < dimension_; ++i) roots.ints.push_back(static_cast<std::int32_t>(roots_[i]));
      out.push_back(std::move(roots));
    }
    return out;
  }

  std::vector<long long> initialCells() const override { return axisOrder(initial_); }

  std::unique_ptr<Discretizer> withInitialCells(const std::vector<long long>& cells) const override {
    const std::string shape = fmt::format("{}", fmt::join(cells, "x"));
    if (cells.size() != static_cast<std::size_t>(dimension_))
      throw Error(fmt::format("kd_tree: expected initial cells for {} axes, found {} ({})", dimension_, cells.size(),
                              shape));
    for (long long n : cells)
      if (n < 1 || n > 1024)
        throw Error(fmt::format("kd_tree: expected initial cells from 1 to 1024 per axis, found {}", shape));
    try {
      return std::make_unique<KdTree>(params_, bounds_, paramOrder(cells));
    } catch (const Error& e) {
      throw Error(fmt::format("kd_tree: cannot start from {} initial cells: {}", shape, e.what()));
    }
  }

  std::unique_ptr<Discretizer> restored(const std::vector<StructureArray>& arrays) const override;

 private:
  // Initial cells from (angle, distance, height) to the tree's axes and back.
  std::vector<long long> axisOrder(const std::array<long long, 3>& c) const {
    if (dimension_ == 1) return {c[1]};
    if (dimension_ == 2) return {c[0], c[1]};
    return {c[0], c[1], c[2]};
  }
  std::array<long long, 3> paramOrder(const std::vector<long long>& cells) const {
    std::array<long long, 3> c = initial_;
    if (dimension_ == 1) c[1] = cells[0];
    else
      for (int i = 0; i < dimension_; ++i) c[i] = cells[i];
    return c;
  }
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
  // The root whose box holds grid coordinates c (the upper one on a shared face, as a split does).
  std::size_t rootOf(const std::array<double, 3>& c) const {
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
  // The box of root r in integer positions.
  void rootBox(std::size_t r, Key& lo, Key& hi) const {
    lo = {0, 0, 0};
    hi = {0, 0, 0};
    for (int i = 0; i < dimension_; ++i) {
      const std::uint64_t j = r % roots_[i];
      r /= roots_[i];
      lo[i] = j * rootKeys(i);
      hi[i] = (j + 1) * rootKeys(i);
    }
  }
  double splitValue(std::size_t n) const { return coordinate(axis_[n], splitKey_[n]); }

  void split(std::size_t n) {
    const int depth = nodeDepth(n);
    const auto low = static_cast<std::int32_t>(axis_.size());
    axis_[n] = sequence_[static_cast<std::size_t>(depth)];
    children_[2 * n] = low;
    children_[2 * n + 1] = low + 1;
    axis_.insert(axis_.end(), {-1, -1});
    children_.insert(children_.end(), {-1, -1, -1, -1});
    depth_.resize(axis_.size(), 0);
    depth_[low] = depth_[low + 1] = depth + 1;
  }

  GridCell find(const std::array<double, 3>& c) const {
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

  // Leaves, vertices and hanging vertices from the nodes (axis_, children_). `source` names
  // the tree in messages. Throws mgrl::Error for a cycle, an unreachable node or a node
  // split on another axis than its depth's.
  void rebuild(const std::string& source);

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
  std::vector<int> sequence_;            // split axis by depth
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

void KdTree::rebuild(const std::string& source) {
  const std::size_t nodes = axis_.size();
  const int d = dimension_;
  depth_.assign(nodes, 0);
  splitKey_.assign(nodes, 0);
  splitCoordinate_.assign(nodes, 0);
  nodeLeaf_.assign(nodes, -1);
  leafNode_.clear();
  leafLoKey_.clear();
  leafHiKey_.clear();
  Key full{0, 0, 0};
  for (int i = 0; i < d; ++i) full[i] = roots_[i] << levels_[i];
  if (nodes < rootCount_)
    throw Error(fmt::format("{}: expected at least the {} roots as nodes, found {} nodes", source, rootCount_, nodes));
  // Depth-first, root by root, low child first: the leaf order. A node reached twice is a
  // cycle, a shared child or a root made a child.
  std::vector<std::uint8_t> seen(nodes, 0);
  struct Item {
    std::size_t node;
    Key lo, hi;
    int depth;
  };
  std::vector<Item> stack;
  for (std::size_t r = rootCount_; r-- > 0;) {
    Item root{r, {}, {}, 0};
    rootBox(r, root.lo, root.hi);
    stack.push_back(root);
  }
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    const std::size_t n = item.node;
    if (seen[n]) throw Error(fmt::format("{}: node {} is reached twice (a cycle or a shared child)", source, n));
    seen[n] = 1;
    depth_[n] = item.depth;
    if (axis_[n] < 0) {
      nodeLeaf_[n] = static_cast<std::int32_t>(leafNode_.size());
      leafNode_.push_back(static_cast<std::int32_t>(n));
      leafLoKey_.push_back(item.lo);
      leafHiKey_.push_back(item.hi);
      continue;
    }
    if (item.depth >= maxDepth_)
      throw Error(fmt::format("{}: node {} at depth {} is split, expected no split below max_depth {}", source, n,
                              item.depth, maxDepth_));
    const int axis = axis_[n];
    if (axis != sequence_[static_cast<std::size_t>(item.depth)])
      throw Error(fmt::format("{}: node {} at depth {} is split on axis {}, expected axis {}", source, n, item.depth,
                              axis, sequence_[static_cast<std::size_t>(item.depth)]));
    const std::uint64_t mid = (item.lo[axis] + item.hi[axis]) / 2;
    splitKey_[n] = mid;
    splitCoordinate_[n] = coordinate(axis, mid);
    Item low = item, high = item;
    low.node = static_cast<std::size_t>(children_[2 * n]);
    high.node = static_cast<std::size_t>(children_[2 * n + 1]);
    low.hi[axis] = mid;
    high.lo[axis] = mid;
    low.depth = high.depth = item.depth + 1;
    stack.push_back(high);
    stack.push_back(low);
  }
  for (std::size_t n = 0; n < nodes; ++n)
    if (!seen[n]) throw Error(fmt::format("{}: node {} is not reachable from a root", source, n));

  // Vertices: leaf corners, numbered by first appearance; a wrapping axis's end is its start.
  const std::size_t leaves = leafNode_.size(), cornerCount = std::size_t{1} << d;
  std::map<Key, std::uint32_t> index;
  std::vector<Key> keys;
  std::vector<std::uint32_t> corners(leaves << d);
  auto canonical = [&](Key k) {
    for (int i = 0; i < d; ++i)
      if (wraps_[i] && k[i] == full[i]) k[i] = 0;
    return k;
  };
  leafLo_.assign(3 * leaves, 0);
  leafHi_.assign(3 * leaves, 0);
  for (std::size_t l = 0; l < leaves; ++l) {
    for (int i = 0; i < d; ++i) {
      leafLo_[3 * l + i] = coordinate(i, leafLoKey_[l][i]);
      leafHi_[3 * l + i] = coordinate(i, leafHiKey_[l][i]);
    }
    for (std::size_t k = 0; k < cornerCount; ++k) {
      Key key{0, 0, 0};
      for (int i = 0; i < d; ++i) key[i] = (k >> i & 1) ? leafHiKey_[l][i] : leafLoKey_[l][i];
      key = canonical(key);
      const auto [it, added] = index.try_emplace(key, static_cast<std::uint32_t>(keys.size()));
      if (added) keys.push_back(key);
      corners[(l << d) | k] = it->second;
    }
  }
  const std::size_t vertices = keys.size();
  vertexCoordinates_.assign(vertices * d, 0);
  for (std::size_t v = 0; v < vertices; ++v)
    for (int i = 0; i < d; ++i) vertexCoordinates_[v * d + i] = coordinate(i, keys[v][i]);

  // Each vertex inside a leaf's box without being its corner is tied to the coarsest such
  // leaf's interpolation (ties: the first leaf).
  std::vector<std::vector<std::pair<std::uint32_t, double>>> tie(vertices);
  std::vector<std::int32_t> found;
  for (std::size_t v = 0; v < vertices; ++v) {
    // On a wrapping axis the start is also the end: look at both images.
    std::vector<Key> images{keys[v]};
    for (int i = 0; i < d; ++i)
      if (wraps_[i] && keys[v][i] == 0) {
        const std::size_t count = images.size();
        for (std::size_t j = 0; j < count; ++j) {
          Key image = images[j];
          image[i] = full[i];
          images.push_back(image);
        }
      }
    std::int32_t best = -1;
    Key bestImage{};
    for (const Key& image : images) {
      found.clear();
      containing(image, found);
      for (std::int32_t leaf : found) {
        if (isCorner(image, leaf)) continue;
        const int depth = depth_[static_cast<std::size_t>(leafNode_[leaf])];
        if (best < 0 || depth < depth_[static_cast<std::size_t>(leafNode_[best])] ||
            (depth == depth_[static_cast<std::size_t>(leafNode_[best])] && leaf < best)) {
          best = leaf;
          bestImage = image;
        }
      }
    }
    if (best < 0) continue;
    for (std::size_t k = 0; k < cornerCount; ++k) {
      double w = 1;
      for (int i = 0; i < d; ++i) {
        const double f = static_cast<double>(bestImage[i] - leafLoKey_[best][i]) /
                         static_cast<double>(leafHiKey_[best][i] - leafLoKey_[best][i]);
        w *= (k >> i & 1) ? f : 1 - f;
      }
      if (w > 0) tie[v].push_back({corners[(static_cast<std::size_t>(best) << d) | k], w});
    }
  }
  // Expanded down to free vertices; a hanging vertex depends only on coarser leaves, so the
  // recursion ends, and a cycle means a corrupt tree.
  std::vector<std::uint8_t> state(vertices, 0);
  std::vector<std::map<std::uint32_t, double>> expanded(vertices);
  auto expand = [&](auto&& self, std::uint32_t v) -> void {
    if (state[v] == 2) return;
    if (state[v] == 1) throw Error(fmt::format("{}: hanging vertices depend on each other in a cycle", source));
    state[v] = 1;
    for (const auto& [u, w] : tie[v]) {
      if (tie[u].empty()) {
        expanded[v][u] += w;
        continue;
      }
      self(self, u);
      for (const auto& [f, fw] : expanded[u]) expanded[v][f] += w * fw;
    }
    state[v] = 2;
  };
  HangingVertices hanging;
  for (std::uint32_t v = 0; v < vertices; ++v) {
    if (tie[v].empty()) continue;
    expand(expand, v);
    hanging.vertex.push_back(v);
    for (const auto& [f, w] : expanded[v]) {
      hanging.source.push_back(f);
      hanging.weight.push_back(static_cast<float>(w));
    }
    hanging.begin.push_back(static_cast<std::uint32_t>(hanging.source.size()));
  }
  setCells(vertices, leaves, std::move(corners), std::move(hanging));
}

void KdTree::containing(const Key& k, std::vector<std::int32_t>& out) const {
  // The roots whose closed box holds k: on each axis the one it is inside, or both around a
  // shared face.
  std::vector<std::size_t> stack{0};
  if (rootCount_ > 1) {
    stack.clear();
    std::array<std::array<std::uint64_t, 2>, 3> along{};
    std::array<int, 3> count{1, 1, 1};
    for (int i = 0; i < dimension_; ++i) {
      const std::uint64_t j = std::min(k[i] / rootKeys(i), roots_[i] - 1);
      along[i] = {j, 0};
      if (k[i] == j * rootKeys(i) && j > 0) {
        along[i][1] = j - 1;
        count[i] = 2;
      }
    }
    for (int a = 0; a < count[0]; ++a)
      for (int b = 0; b < count[1]; ++b)
        for (int c = 0; c < count[2]; ++c)
          stack.push_back(static_cast<std::size_t>(along[0][a] + roots_[0] * (along[1][b] + roots_[1] * along[2][c])));
  }
  while (!stack.empty()) {
    const std::size_t n = stack.back();
    stack.pop_back();
    if (axis_[n] < 0) {
      out.push_back(nodeLeaf_[n]);
      continue;
    }
    const int axis = axis_[n];
    if (k[axis] <= splitKey_[n]) stack.push_back(static_cast<std::size_t>(children_[2 * n]));
    if (k[axis] >= splitKey_[n]) stack.push_back(static_cast<std::size_t>(children_[2 * n + 1]));
  }
}

void KdTree::freeCorners(const std::vector<Key>& keys) {
  // Every image of each key (on a wrapping axis the start is also the end).
  Key full{0, 0, 0};
  for (int i = 0; i < dimension_; ++i) full[i] = roots_[i] << levels_[i];
  std::vector<Key> images;
  for (const Key& key : keys) {
    const std::size_t first = images.size();
    images.push_back(key);
    for (int i = 0; i < dimension_; ++i)
      if (wraps_[i] && (key[i] == 0 || key[i] == full[i])) {
        const std::size_t count = images.size();
        for (std::size_t j = first; j < count; ++j) {
          Key image = images[j];
          image[i] = key[i] == 0 ? full[i] : 0;
          images.push_back(image);
        }
      }
  }
  std::sort(images.begin(), images.end());
  images.erase(std::unique(images.begin(), images.end()), images.end());
  std::vector<std::int32_t> found;
  std::vector<std::size_t> nodes;
  // Each pass splits a leaf once, at its own depth's axis; a leaf coarser than the key's
  // level needs several passes. max_depth bounds the passes.
  for (int pass = 0; pass <= maxDepth_; ++pass) {
    nodes.clear();
    for (const Key& image : images) {
      found.clear();
      containing(image, found);
      for (std::int32_t leaf : found) {
        const auto node = static_cast<std::size_t>(leafNode_[leaf]);
        if (!isCorner(image, leaf) && nodeDepth(node) < maxDepth_) nodes.push_back(node);
      }
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    if (nodes.empty()) return;
    for (std::size_t n : nodes) split(n);
    rebuild("kd_tree");
  }
}

std::unique_ptr<Discretizer> KdTree::restored(const std::vector<StructureArray>& arrays) const {
  // A tree that adaptive_value_iteration grew from other initial cells says which.
  for (const StructureArray& a : arrays) {
    if (a.name != "start_cells") continue;
    const std::string where = a.source.empty() ? a.name : a.source;
    const auto d = static_cast<std::size_t>(dimension_);
    if (!a.integer || a.shape != std::vector<std::size_t>{d})
      throw Error(fmt::format("{}: expected {} int32 initial cells (one per axis), found {} {}", where, d,
                              a.integer ? "int32" : "float64", formatShape(a.shape)));
    std::unique_ptr<Discretizer> start;
    try {
      start = withInitialCells(std::vector<long long>(a.ints.begin(), a.ints.end()));
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}", where, e.what()));
    }
    return static_cast<const KdTree&>(*start).restoredFrom(arrays);
  }
  return restoredFrom(arrays);
}

std::unique_ptr<Discretizer> KdTree::restoredFrom(const std::vector<StructureArray>& arrays) const {
  auto get = [&](std::string_view name, bool integer) -> const StructureArray& {
    for (const StructureArray& a : arrays)
      if (a.name == name) {
        if (a.integer != integer)
          throw Error(fmt::format("{}: expected {} values, found {}", a.source.empty() ? a.name : a.source,
                                  integer ? "int32" : "float64", integer ? "float64" : "int32"));
        return a;
      }
    throw Error(fmt::format("{}: kd_tree: expected the tree array '{}', found none",
                            arrays.empty() ? std::string("policy bundle") : arrays[0].source, name));
  };
  auto where = [](const StructureArray& a) { return a.source.empty() ? a.name : a.source; };
  const StructureArray& bounds = get("bounds", false);
  const auto d = static_cast<std::size_t>(dimension_);
  if (bounds.shape != std::vector<std::size_t>{d, 2})
    throw Error(fmt::format("{}: expected shape ({}, 2) for the scenario's {}-dimensional kd_tree, found {} (a "
                            "tree of another dimension)",
                            where(bounds), d, d, formatShape(bounds.shape)));
  for (std::size_t i = 0; i < d; ++i)
    if (std::fabs(bounds.reals[2 * i] - lo_[i]) > 1e-9 * (1 + std::fabs(lo_[i])) ||
        std::fabs(bounds.reals[2 * i + 1] - (lo_[i] + span_[i])) > 1e-9 * (1 + std::fabs(lo_[i] + span_[i])))
      throw Error(fmt::format("{}: expected the bounds of the scenario's tree on axis {} ([{}, {}]), found [{}, {}]",
                              where(bounds), i, lo_[i], lo_[i] + span_[i], bounds.reals[2 * i],
                              bounds.reals[2 * i + 1]));
  // The roots: written for forests only, so a bundle without them has one root.
  std::vector<std::int32_t> roots(d, 1);
  const StructureArray* rootArray = nullptr;
  for (const StructureArray& a : arrays)
    if (a.name == "roots") rootArray = &get("roots", true);
  if (rootArray) {
    if (rootArray->shape != std::vector<std::size_t>{d})
      throw Error(fmt::format("{}: expected shape ({},) (root boxes per axis), found {}", where(*rootArray), d,
                              formatShape(rootArray->shape)));
    roots = rootArray->ints;
  }
  for (std::size_t i = 0; i < d; ++i)
    if (roots[i] != static_cast<std::int32_t>(roots_[i]))
      throw Error(fmt::format("{}: expected {} root boxes on axis {} as the tree's initial cells make, found {}",
                              rootArray ? where(*rootArray) : where(bounds), roots_[i], i, roots[i]));
  const StructureArray& axis = get("split_axis", true);
  const StructureArray& value = get("split_value", false);
  const StructureArray& children = get("children", true);
  const StructureArray& leafCorners = get("leaf_corners", true);
  const std::size_t nodes = axis.ints.size();
  if (axis.shape.size() != 1 || nodes < rootCount_ || nodes > 2 * kMaxGridVertices)
    throw Error(fmt::format("{}: expected shape (N,) with N >= {} nodes (the roots), found {}", where(axis),
                            rootCount_, formatShape(axis.shape)));
  if (value.shape != std::vector<std::size_t>{nodes})
    throw Error(fmt::format("{}: expected shape ({},) like split_axis, found {}", where(value), nodes,
                            formatShape(value.shape)));
  if (children.shape != std::vector<std::size_t>{nodes, 2})
    throw Error(fmt::format("{}: expected shape ({}, 2) like split_axis, found {}", where(children), nodes,
                            formatShape(children.shape)));
  for (std::size_t n = 0; n < nodes; ++n) {
    const std::int32_t a = axis.ints[n], low = children.ints[2 * n], high = children.ints[2 * n + 1];
    if (a < -1 || a >= dimension_)
      throw Error(fmt::format("{}: node {}: expected a split axis in [-1, {}], found {}", where(axis), n,
                              dimension_ - 1, a));
    const bool leaf = a < 0;
    if (leaf && (low != -1 || high != -1))
      throw Error(fmt::format("{}: node {} is a leaf (split axis -1), expected children -1 -1, found {} {}",
                              where(children), n, low, high));
    const auto first = static_cast<std::int32_t>(rootCount_);  // roots are nobody's children
    if (!leaf && (low < first || high < first || static_cast<std::size_t>(low) >= nodes ||
                  static_cast<std::size_t>(high) >= nodes || low == high))
      throw Error(fmt::format("{}: node {}: expected two distinct children in [{}, {}), found {} {} (out of range)",
                              where(children), n, first, nodes, low, high));
  }
  auto copy = std::make_unique<KdTree>(*this);
  copy->axis_ = axis.ints;
  copy->children_ = children.ints;
  copy->depth_.assign(nodes, 0);
  copy->rebuild(where(children));
  for (std::size_t n = 0; n < nodes; ++n)
    if (copy->axis_[n] >= 0 &&
        !(std::fabs(value.reals[n] - copy->splitValue(n)) <= 1e-9 * (1 + std::fabs(copy->splitValue(n)))))
      throw Error(fmt::format("{}: node {}: expected the midpoint {} of its box, found {}", where(value), n,
                              copy->splitValue(n), value.reals[n]));
  const std::size_t cornerCount = std::size_t{1} << dimension_;
  if (leafCorners.shape != std::vector<std::size_t>{copy->leafNode_.size(), cornerCount})
    throw Error(fmt::format("{}: expected shape ({}, {}) (the tree's leaves and their corners), found {}",
                            where(leafCorners), copy->leafNode_.size(), cornerCount,
                            formatShape(leafCorners.shape)));
  for (std::size_t k = 0; k < leafCorners.ints.size(); ++k)
    if (leafCorners.ints[k] != static_cast<std::int32_t>(copy->cellCorners()[k]))
      throw Error(fmt::format("{}: leaf {} corner {}: expected vertex {} as the tree numbers them, found {}",
                              where(leafCorners), k / cornerCount, k % cornerCount, copy->cellCorners()[k],
                              leafCorners.ints[k]));
  return copy;
}

}  // namespace

void registerKdTree(DiscretizerRegistry& registry) {
  registry.add(
      {"kd_tree",
       "adaptive grid (Munos & Moore 2002's kd-trie): boxes split at their midpoints, values at box corners, "
       "multilinear inside a box and continuous across faces (hanging corners tied to the coarse face); refined by "
       "adaptive_value_iteration",
       withBounds(
           {ParamSpec::choice("coordinates", "cylindrical", {"distance", "polar", "cylindrical"},
                              "distance: ground distance straight ahead (1-D); polar: angle x distance as polar2d; "
                              "cylindrical: angle x distance x height as cylindrical3d"),
            ParamSpec::integer("angle_cells", 4, 1, 1024, "cells",
                               "initial cells along the angle (n = r x 2^p, r odd: r root boxes split p times)"),
            ParamSpec::integer("distance_cells", 4, 1, 1024, "cells",
                               "initial cells along the distance (as angle_cells)"),
            ParamSpec::integer("height_cells", 2, 1, 1024, "cells", "initial cells along the height (as angle_cells)"),
            ParamSpec::integer("max_depth", 24, 0, 90, "splits",
                               "no leaf is split more often than this below its root "
                               "box (initial splits included)"),
            ParamSpec::choice(
                "split_axes", "round_robin", {"round_robin", "longest"},
                "the axis each depth past the initial cells halves: round_robin: every axis in turn; "
                "longest: the axis whose cells are then longest in metres (angles as the arc at the middle "
                "distance)"),
            ParamSpec::choice(
                "refinement", "local", {"local", "conforming"},
                "how a leaf is split when refined: local: that leaf only (the corners of its new face hang "
                "on its coarser neighbours and add no free value); conforming: also the neighbours around "
                "the new face's corners, down to the leaf's new depth, so that those corners are free"),
            ParamSpec::number("height", 0.0, -10, 10, "m", "distance, polar: the height of the target's position")},
           {.lowestDistance = -100}),
       [](const Params& p, const StateActionModel& m) { return std::make_unique<KdTree>(p, m); }});
}

}  // namespace mgrl::discretizers
