// kd_tree's structure (kd_tree.hpp): splitting nodes, deriving the leaves, vertices and
// hanging vertices from the nodes (rebuild), and refinement, local or conforming. This is
// where the continuity invariant is made: every hanging corner tied to the coarse face it
// lies in.
#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "kd_tree.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl::discretizers {

void KdTree::split(std::size_t n) {
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

void KdTree::rootBox(std::size_t r, Key& lo, Key& hi) const {
  lo = {0, 0, 0};
  hi = {0, 0, 0};
  for (int i = 0; i < dimension_; ++i) {
    const std::uint64_t j = r % roots_[i];
    r /= roots_[i];
    lo[i] = j * rootKeys(i);
    hi[i] = (j + 1) * rootKeys(i);
  }
}

void KdTree::rebuild(const std::string& source) {
  numberLeaves(source);
  std::vector<std::uint32_t> corners;
  const std::vector<Key> keys = numberVertices(corners);
  HangingVertices hanging = hangingVertices(keys, corners, source);
  setCells(keys.size(), leafNode_.size(), std::move(corners), std::move(hanging));
}

void KdTree::numberLeaves(const std::string& source) {
  const std::size_t nodes = axis_.size();
  depth_.assign(nodes, 0);
  splitKey_.assign(nodes, 0);
  splitCoordinate_.assign(nodes, 0);
  nodeLeaf_.assign(nodes, -1);
  leafNode_.clear();
  leafLoKey_.clear();
  leafHiKey_.clear();
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
}

std::vector<KdTree::Key> KdTree::numberVertices(std::vector<std::uint32_t>& corners) {
  const int d = dimension_;
  const Key full = fullKey();
  // Vertices: leaf corners, numbered by first appearance; a wrapping axis's end is its start.
  const std::size_t leaves = leafNode_.size(), cornerCount = std::size_t{1} << d;
  std::map<Key, std::uint32_t> index;
  std::vector<Key> keys;
  corners.assign(leaves << d, 0);
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
  return keys;
}

HangingVertices KdTree::hangingVertices(const std::vector<Key>& keys, const std::vector<std::uint32_t>& corners,
                                        const std::string& source) const {
  const int d = dimension_;
  const Key full = fullKey();
  const std::size_t vertices = keys.size(), cornerCount = std::size_t{1} << d;
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
  return hanging;
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

std::unique_ptr<Discretizer> KdTree::refined(const std::vector<std::uint32_t>& cells) const {
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
        key[i] = i == axis      ? (leafLoKey_[cell][i] + leafHiKey_[cell][i]) / 2
                 : (k >> i & 1) ? leafHiKey_[cell][i]
                                : leafLoKey_[cell][i];
      faceCorners.push_back(key);
    }
    copy->split(node);
  }
  copy->rebuild("kd_tree");
  if (conforming_) copy->freeCorners(faceCorners);
  return copy;
}

void KdTree::freeCorners(const std::vector<Key>& keys) {
  // Every image of each key (on a wrapping axis the start is also the end).
  const Key full = fullKey();
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

}  // namespace mgrl::discretizers
