// kd_tree's parameters (kd_tree.hpp: the tree, its invariant and its parts): the initial
// cells as root boxes split a few times, the split axis of every depth, the initial tree,
// and the plug-in's registration.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "discretizers.hpp"
#include "kd_tree.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl::discretizers {

KdTree::KdTree(const Params& p, const StateActionModel& m)
    : KdTree(p, chosenBounds(p, m, p.choice("coordinates") == "cylindrical"),
             {p.integer("angle_cells"), p.integer("distance_cells"), p.integer("height_cells")}) {}

KdTree::KdTree(const Params& p, const Bounds& b, const std::array<long long, 3>& initial)
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
  // The initial tree's vertices are checked before any node is made.
  double initialVertices = 1;
  for (int i = 0; i < dimension_; ++i)
    initialVertices *= static_cast<double>(roots_[i] * cells[i]) + (wraps_[i] ? 0 : 1);
  if (initialVertices > static_cast<double>(kMaxGridVertices))
    p.fail(dimension_ == 1 ? "distance_cells" : "angle_cells",
           fmt::format("expected initial cells ({}) with at most {} vertices, found {} vertices",
                       dimension_ == 1   ? "distance"
                       : dimension_ == 2 ? "angle x distance"
                                         : "angle x distance x height",
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
    p.fail("max_depth",
           fmt::format("expected at least the {} splits of the initial cells, found {}", initialDepth_, maxDepth_));
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
    // continuity argument (kd_tree.hpp) holds.
    std::array<double, 3> length{0, 0, 0};
    const double radius = dimension_ > 1 ? std::max(0.5 * (b.distance[0] + b.distance[1]), 0.1) : 1.0;
    for (int i = 0; i < dimension_; ++i) {
      int halvings = 0;
      for (int axis : sequence_) halvings += axis == i ? 1 : 0;
      length[i] =
          std::ldexp(span_[i] * (i == 0 && dimension_ > 1 ? radius : 1.0), -halvings) / static_cast<double>(roots_[i]);
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

std::array<long long, 3> KdTree::paramOrder(const std::vector<long long>& cells) const {
  std::array<long long, 3> c = initial_;
  if (dimension_ == 1)
    c[1] = cells[0];
  else
    for (int i = 0; i < dimension_; ++i) c[i] = cells[i];
  return c;
}

std::unique_ptr<Discretizer> KdTree::withInitialCells(const std::vector<long long>& cells) const {
  const std::string shape = fmt::format("{}", fmt::join(cells, "x"));
  if (cells.size() != static_cast<std::size_t>(dimension_))
    throw Error(
        fmt::format("kd_tree: expected initial cells for {} axes, found {} ({})", dimension_, cells.size(), shape));
  for (long long n : cells)
    if (n < 1 || n > 1024)
      throw Error(fmt::format("kd_tree: expected initial cells from 1 to 1024 per axis, found {}", shape));
  try {
    return std::make_unique<KdTree>(params_, bounds_, paramOrder(cells));
  } catch (const Error& e) {
    throw Error(fmt::format("kd_tree: cannot start from {} initial cells: {}", shape, e.what()));
  }
}

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
