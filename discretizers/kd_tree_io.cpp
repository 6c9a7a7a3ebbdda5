// kd_tree as data (kd_tree.hpp): its description, the arrays a policy bundle saves (the
// nodes, the leaves' corners, the vertices' coordinates; the roots and the start only when
// they differ from what the parameters make) and the tree rebuilt from them, checked
// against the scenario's parameters array by array.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "kd_tree.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl::discretizers {

nlohmann::json KdTree::describe() const {
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

std::vector<StructureArray> KdTree::structure() const {
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
  StructureArray coordinates{
      "vertex_coordinates", {vertexCount(), static_cast<std::size_t>(dimension_)}, {}, vertexCoordinates_, false, {}};
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
    throw Error(
        fmt::format("{}: expected shape ({}, 2) for the scenario's {}-dimensional kd_tree, found {} (a "
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
    throw Error(fmt::format("{}: expected shape (N,) with N >= {} nodes (the roots), found {}", where(axis), rootCount_,
                            formatShape(axis.shape)));
  if (value.shape != std::vector<std::size_t>{nodes})
    throw Error(fmt::format("{}: expected shape ({},) like split_axis, found {}", where(value), nodes,
                            formatShape(value.shape)));
  if (children.shape != std::vector<std::size_t>{nodes, 2})
    throw Error(fmt::format("{}: expected shape ({}, 2) like split_axis, found {}", where(children), nodes,
                            formatShape(children.shape)));
  for (std::size_t n = 0; n < nodes; ++n) {
    const std::int32_t a = axis.ints[n], low = children.ints[2 * n], high = children.ints[2 * n + 1];
    if (a < -1 || a >= dimension_)
      throw Error(
          fmt::format("{}: node {}: expected a split axis in [-1, {}], found {}", where(axis), n, dimension_ - 1, a));
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
                            where(leafCorners), copy->leafNode_.size(), cornerCount, formatShape(leafCorners.shape)));
  for (std::size_t k = 0; k < leafCorners.ints.size(); ++k)
    if (leafCorners.ints[k] != static_cast<std::int32_t>(copy->cellCorners()[k]))
      throw Error(fmt::format("{}: leaf {} corner {}: expected vertex {} as the tree numbers them, found {}",
                              where(leafCorners), k / cornerCount, k % cornerCount, copy->cellCorners()[k],
                              leafCorners.ints[k]));
  return copy;
}

}  // namespace mgrl::discretizers
