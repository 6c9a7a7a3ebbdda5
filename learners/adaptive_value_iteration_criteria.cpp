// adaptive_value_iteration's splitting criteria (adaptive_value_iteration.hpp): Munos &
// Moore 2002's local ones, value non-linearity and policy disagreement (their section
// "splitting methods based on local considerations"), and their non-local influence x
// standard deviation; score() rates every leaf, choose() picks the leaves to split.
#include <algorithm>
#include <cmath>

#include "adaptive_value_iteration.hpp"
#include "mgrl/core/parallel.hpp"

namespace mgrl::learners {

namespace {

// The influence and variance fixed points stop at this relative change or sweep count.
constexpr double kInfluenceTolerance = 1e-4;
constexpr int kInfluenceSweeps = 2000;

// Influence and standard deviation at every (motion state, vertex), index s * V + v.
struct InfluenceField {
  std::vector<double> influence, deviation;
  int sweeps = 0;
};

// Munos & Moore 2002, "influence" and "variance": the greedy policy on the current
// solution, with the interpolation at the successor read as a transition to the corners
// of its cell with probabilities the weights (hanging corners passed on to their sources).
// sigma^2(x) = gamma^2 sum_k w_k (V(c_k) - sum_j w_j V(c_j))^2 + gamma^2 sum_k w_k sigma^2(c_k)
// and I(x) = 1 + sum_y gamma(y) p(x | y) I(y), both fixed points of a contraction, iterated
// to a relative change below `tolerance` (at most `maxSweeps` sweeps). The variance sweeps
// gather (parallel, deterministic); the influence sweeps scatter, serially so that the
// sums are formed in one order.
InfluenceField influenceField(const GridModel& g, const QTable& q, double tolerance, int maxSweeps, unsigned threads) {
  const std::size_t V = g.vertexCount, states = q.stateCount();
  const int d = g.dimension, corners = 1 << d;
  std::vector<std::int32_t> tiedAt(V, -1);
  for (std::size_t i = 0; i < g.hanging.size(); ++i) tiedAt[g.hanging.vertex[i]] = static_cast<std::int32_t>(i);
  std::vector<std::int64_t> greedy(states * V, -1);
  std::vector<double> value(states * V, 0.0);
  parallelFor(states, threads, [&](std::size_t s, unsigned) {
    const std::size_t n = q.actionsOf(s);
    if (n == 0) return;
    for (std::size_t v = 0; v < V; ++v) {
      const float* row = q.row(s, v);
      const auto best = static_cast<std::size_t>(std::max_element(row, row + n) - row);
      greedy[s * V + v] = static_cast<std::int64_t>(g.stateActionBegin[s] + best);
      value[s * V + v] = row[best];
    }
  });
  // The motion state the greedy action at (s, v) ends at, if its target stays in the grid.
  auto successorState = [&](std::size_t s, std::size_t v, std::size_t& next) {
    const std::int64_t a = greedy[s * V + v];
    if (a < 0 || g.transition[static_cast<std::size_t>(a) * V + v].cell < 0) return false;
    next = g.actionTo[static_cast<std::size_t>(a)];
    return true;
  };
  // Calls f(vertex, weight) for the free vertices that the successor of (s, v) lands on.
  auto successors = [&](std::size_t s, std::size_t v, auto&& f) {
    const std::int64_t a = greedy[s * V + v];
    if (a < 0) return;
    const GridTransition& t = g.transition[static_cast<std::size_t>(a) * V + v];
    if (t.cell < 0) return;
    float w[8];
    cornerWeights(d, {t.frac[0], t.frac[1], t.frac[2]}, w);
    const std::uint32_t* c = &g.corners[static_cast<std::size_t>(t.cell) << d];
    for (int k = 0; k < corners; ++k) {
      if (w[k] == 0) continue;
      const std::int32_t tie = tiedAt[c[k]];
      if (tie < 0) {
        f(c[k], static_cast<double>(w[k]));
        continue;
      }
      for (std::uint32_t j = g.hanging.begin[tie]; j < g.hanging.begin[tie + 1]; ++j)
        f(g.hanging.source[j], static_cast<double>(w[k]) * g.hanging.weight[j]);
    }
  };
  InfluenceField out;
  std::vector<double> variance(states * V, 0.0), nextVariance(states * V, 0.0);
  std::vector<double> change(states, 0.0);
  for (int sweep = 0; sweep < maxSweeps; ++sweep) {
    parallelFor(states, threads, [&](std::size_t s, unsigned) {
      double largest = 0;
      for (std::size_t v = 0; v < V; ++v) {
        if (tiedAt[v] >= 0) continue;
        const std::int64_t a = greedy[s * V + v];
        double square = 0, carried = 0;
        std::size_t next = 0;
        if (successorState(s, v, next)) {
          // The weighted mean of the successor corners' values, then the spread about it.
          double m = 0;
          successors(s, v, [&](std::uint32_t u, double w) { m += w * value[next * V + u]; });
          successors(s, v, [&](std::uint32_t u, double w) {
            const double gap = value[next * V + u] - m;
            square += w * gap * gap;
            carried += w * variance[next * V + u];
          });
        }
        const double gamma = a >= 0 ? g.discount[static_cast<std::size_t>(a)] : 0.0;
        const double updated = gamma * gamma * (square + carried);
        largest = std::max(largest, std::fabs(updated - variance[s * V + v]));
        nextVariance[s * V + v] = updated;
      }
      change[s] = largest;
    });
    std::swap(variance, nextVariance);
    out.sweeps = std::max(out.sweeps, sweep + 1);
    const double scale = *std::max_element(variance.begin(), variance.end());
    if (*std::max_element(change.begin(), change.end()) <= tolerance * (scale + 1e-30)) break;
  }
  std::vector<double> influence(states * V, 0.0), nextInfluence(states * V, 0.0);
  for (int sweep = 0; sweep < maxSweeps; ++sweep) {
    for (std::size_t i = 0; i < states * V; ++i) nextInfluence[i] = tiedAt[i % V] >= 0 ? 0.0 : 1.0;
    for (std::size_t s = 0; s < states; ++s)
      for (std::size_t v = 0; v < V; ++v) {
        const std::int64_t a = greedy[s * V + v];
        if (a < 0 || tiedAt[v] >= 0) continue;
        const double mass = g.discount[static_cast<std::size_t>(a)] * influence[s * V + v];
        std::size_t next = 0;
        if (!successorState(s, v, next)) continue;
        successors(s, v, [&](std::uint32_t u, double w) { nextInfluence[next * V + u] += w * mass; });
      }
    double largest = 0, scale = 0;
    for (std::size_t i = 0; i < states * V; ++i) {
      largest = std::max(largest, std::fabs(nextInfluence[i] - influence[i]));
      scale = std::max(scale, nextInfluence[i]);
    }
    std::swap(influence, nextInfluence);
    out.sweeps = std::max(out.sweeps, sweep + 1);
    if (largest <= tolerance * scale) break;
  }
  out.influence = std::move(influence);
  out.deviation.resize(states * V);
  for (std::size_t i = 0; i < states * V; ++i) out.deviation[i] = std::sqrt(variance[i]);
  return out;
}

}  // namespace

double backedUpValue(const Problem& problem, const Discretizer& grid, const GridModel& g, const QTable& q,
                     std::size_t s, const Eigen::Vector3d& e) {
  const StateActionModel& m = problem.model;
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < q.actionsOf(s); ++j) {
    const std::size_t a = m.stateActionBegin[s] + j;
    double value = problem.reward.evaluate(m, a, e);
    GridCell next;
    if (grid.locate(problem.environment.next(m, a, e), next))
      value += g.discount[a] * maxInterpolated(q, g, g.actionTo[a], next.cell, next.frac.data());
    best = std::max(best, value);
  }
  return best;
}

LeafScores AdaptiveValueIteration::score(const Problem& problem, const Discretizer& grid, const GridModel& g,
                                         const QTable& q, unsigned threads) const {
  const std::size_t leaves = grid.cellCount(), states = q.stateCount();
  const int corners = 1 << grid.dimension();
  std::size_t widest = 0;
  for (std::size_t s = 0; s < states; ++s) widest = std::max(widest, q.actionsOf(s));
  LeafScores out{std::vector<double>(leaves, 0.0), std::vector<double>(leaves, 0.0), {}};
  const bool byInfluence = criterion_ == "influence" || criterion_ == "influence_policy";
  InfluenceField field;
  std::vector<std::uint8_t> tied(grid.vertexCount(), 0);
  if (byInfluence) {
    field = influenceField(g, q, kInfluenceTolerance, kInfluenceSweeps, threads);
    out.influence.assign(leaves, 0.0);
    for (std::uint32_t v : grid.hanging().vertex) tied[v] = 1;
  }
  const std::size_t V = grid.vertexCount();
  parallelFor(leaves, threads, [&](std::size_t leaf, unsigned) {
    const Eigen::Vector3d centre = grid.cellCentre(static_cast<std::uint32_t>(leaf));
    GridCell cell;
    if (!grid.locate(centre, cell)) return;
    const Stencil stencil = grid.stencil(cell);
    std::vector<float> sum(widest + QTable::kPadding);
    double valueGap = 0, disagreements = 0, influence = 0;
    for (std::size_t s = 0; s < states; ++s) {
      const std::size_t n = q.actionsOf(s);
      if (n == 0) continue;
      // Value non-linearity: V_s at the centre by one backup of each out-action against V_s
      // interpolated from the corners.
      const double backedUp = backedUpValue(problem, grid, g, q, s, centre);
      std::fill(sum.begin(), sum.end(), 0.0f);
      addInterpolated(sum.data(), q, static_cast<std::uint32_t>(s), stencil, 1.0f);
      const double interpolatedValue = *std::max_element(sum.begin(), sum.begin() + static_cast<std::ptrdiff_t>(n));
      valueGap += std::fabs(backedUp - interpolatedValue);
      // Policy disagreement: the greedy action of every corner.
      std::size_t first = 0;
      bool differ = false;
      for (int k = 0; k < corners; ++k) {
        const float* row = q.row(s, stencil.vertex[k]);
        const auto best = static_cast<std::size_t>(std::max_element(row, row + n) - row);
        if (k == 0)
          first = best;
        else
          differ = differ || best != first;
      }
      disagreements += differ ? 1 : 0;
      if (byInfluence && (differ || criterion_ == "influence")) {
        double largest = 0;
        for (int k = 0; k < corners; ++k) {
          const std::uint32_t v = stencil.vertex[k];
          if (!tied[v]) largest = std::max(largest, field.influence[s * V + v] * field.deviation[s * V + v]);
        }
        influence += largest;
      }
    }
    if (byInfluence) out.influence[leaf] = influence;
    out.value[leaf] = valueGap / static_cast<double>(states);
    out.policy[leaf] = disagreements / static_cast<double>(states);
  });
  return out;
}

// The leaves to split this round: the highest ranked by the criterion (ties: lower leaf
// index), a fraction of the leaves, no more than the vertex budget allows (a split adds at
// most 2^(d-1) vertices, the corners of the new face).
std::vector<std::uint32_t> AdaptiveValueIteration::choose(const Discretizer& grid, const LeafScores& scores) const {
  const std::size_t leaves = grid.cellCount();
  const std::size_t perSplit = std::size_t{1} << (grid.dimension() - 1);
  const std::size_t used = counted(grid);
  const std::size_t room = used >= maxVertices_ ? 0 : (maxVertices_ - used) / perSplit;
  const std::size_t wanted = std::min(
      room,
      std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(splitFraction_ * static_cast<double>(leaves)))));
  auto ranked = [&](const std::vector<double>& score, double threshold) {
    std::vector<std::uint32_t> order;
    for (std::uint32_t l = 0; l < leaves; ++l)
      if (score[l] > threshold && grid.splittable(l)) order.push_back(l);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return score[a] > score[b]; });
    return order;
  };
  if (!scores.influence.empty()) {
    // influence: the largest influence x deviation; influence_policy: the same among the
    // leaves whose corners disagree (the score is 0 for the others).
    std::vector<std::uint32_t> order = ranked(scores.influence, 0.0);
    if (order.size() > wanted) order.resize(wanted);
    return order;
  }
  const std::vector<std::uint32_t> byValue =
      criterion_ == "policy" ? std::vector<std::uint32_t>{} : ranked(scores.value, splitTolerance_);
  const std::vector<std::uint32_t> byPolicy =
      criterion_ == "value" ? std::vector<std::uint32_t>{} : ranked(scores.policy, 0.0);
  // "both": the two rankings taken in turn (Munos & Moore's combination of the two criteria).
  std::vector<std::uint32_t> chosen;
  std::vector<std::uint8_t> taken(leaves, 0);
  for (std::size_t i = 0; chosen.size() < wanted && (i < byValue.size() || i < byPolicy.size()); ++i)
    for (const std::vector<std::uint32_t>* list : {&byValue, &byPolicy})
      if (i < list->size() && chosen.size() < wanted && !taken[(*list)[i]]) {
        taken[(*list)[i]] = 1;
        chosen.push_back((*list)[i]);
      }
  return chosen;
}

}  // namespace mgrl::learners
