#include "mgrl/learning/policy_evaluation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"

namespace mgrl {

namespace {

// The corners and weights of the point with cell `cell` and fractions `frac`, as
// maxInterpolated() weighs them (the products in cornerWeights' order).
Stencil stencilOf(const GridModel& g, std::uint32_t cell, const float* frac) {
  Stencil st;
  const int d = g.dimension;
  st.size = 1 << d;
  cornerWeights(d, {frac[0], frac[1], frac[2]}, st.weight.data());
  const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(cell) << d];
  for (int k = 0; k < st.size; ++k) st.vertex[k] = corner[k];
  return st;
}

constexpr std::uint16_t kOutside = std::numeric_limits<std::uint16_t>::max();

// Action j's value interpolated at the point with cell `cell` and fractions `frac`, from the
// block of its state's rows (vertex u's row at block + u * n).
inline float interpolatedAt(const float* block, std::size_t n, std::size_t j, const GridModel& g, std::uint32_t cell,
                            const float* frac) {
  const int d = g.dimension;
  const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(cell) << d];
  if (d == 3) {
    // maxInterpolated()'s products, written out.
    const float f0 = frac[0], f1 = frac[1], f2 = frac[2], g0 = 1 - f0, g1 = 1 - f1, g2 = 1 - f2;
    const float w[8] = {g0 * g1 * g2, f0 * g1 * g2, g0 * f1 * g2, f0 * f1 * g2,
                        g0 * g1 * f2, f0 * g1 * f2, g0 * f1 * f2, f0 * f1 * f2};
    float sum = 0;
    for (int k = 0; k < 8; ++k) sum += w[k] * block[corner[k] * n + j];
    return sum;
  }
  float w[8];
  cornerWeights(d, {frac[0], frac[1], frac[2]}, w);
  float sum = 0;
  for (int k = 0; k < (1 << d); ++k) sum += w[k] * block[corner[k] * n + j];
  return sum;
}

}  // namespace

PolicyValues evaluateGreedy(const QTable& policy, const GridModel& g, const StateActionModel& model, unsigned threads,
                            double tolerance, int maxSweeps, const QTable* start) {
  const std::size_t V = g.vertexCount, A = g.actionCount;
  if (!g.hanging.empty())
    throw Error("policy evaluation: expected a fixed grid, found one with hanging vertices (an adaptive grid)");
  if (g.transition.empty() && !g.compact())
    throw Error("policy evaluation: expected a tabulated or compact model, found the model's frame only");
  if (policy.vertexCount() != V || policy.actionCount() != A)
    throw Error(fmt::format("policy evaluation: expected a table of {} actions x {} vertices, found {} x {}", A, V,
                            policy.actionCount(), policy.vertexCount()));
  // The policy's choice where each (action, vertex) lands: the index among the end state's
  // out-actions (an end state has fewer than 65,535 of them: checked), computed once.
  std::vector<std::uint16_t> chosen(A * V, kOutside);
  for (std::size_t s = 0; s < policy.stateCount(); ++s)
    if (policy.actionsOf(s) >= kOutside)
      throw Error(fmt::format("policy evaluation: graph state {} has {} out-actions, expected fewer than {}", s,
                              policy.actionsOf(s), kOutside));
  parallelFor(A, threads, [&](std::size_t a, unsigned) {
    const std::uint32_t s = g.actionTo[a];
    const std::size_t n = policy.actionsOf(s);
    std::vector<float> scores(n + 16);
    for (std::size_t v = 0; v < V; ++v) {
      const GridTransition t = g.at(a, v);
      if (t.cell < 0) continue;
      std::fill(scores.begin(), scores.end(), 0.0F);
      addInterpolated(scores.data(), policy, s, stencilOf(g, static_cast<std::uint32_t>(t.cell), t.frac), 1.0F);
      std::size_t best = 0;
      for (std::size_t j = 1; j < n; ++j)
        if (scores[j] > scores[best]) best = j;
      chosen[a * V + v] = static_cast<std::uint16_t>(best);
    }
  });
  if (start && (start->vertexCount() != V || start->actionCount() != A))
    throw Error(fmt::format("policy evaluation: expected a start table of {} actions x {} vertices, found {} x {}", A,
                            V, start->actionCount(), start->vertexCount()));
  PolicyValues out{start ? *start : QTable(model, V)};
  QTable next(model, V);
  // Jacobi sweeps: each action's values from the last sweep's table only, so the order of
  // the actions (and the threads) does not matter. Actions grouped by the state they end
  // at, as sweep() groups them: a group reads one block of the table, which stays in cache.
  const std::size_t states = g.incomingBegin.size() - 1;
  std::vector<double> change(states, 0.0);
  while (out.sweeps < maxSweeps) {
    parallelFor(states, threads, [&](std::size_t s, unsigned) {
      const std::size_t n = out.q.actionsOf(s);
      const float* block = out.q.row(s, 0);  // vertex u's row starts at block + u * n
      double largest = 0;
      for (std::uint32_t i = g.incomingBegin[s]; i < g.incomingBegin[s + 1]; ++i) {
        const std::size_t a = g.incoming[i];
        for (std::size_t v = 0; v < V; ++v) {
          const GridTransition t = g.at(a, v);
          float value = t.reward;
          if (t.cell >= 0)
            value += g.discount[a] *
                     interpolatedAt(block, n, chosen[a * V + v], g, static_cast<std::uint32_t>(t.cell), t.frac);
          largest = std::max(largest, static_cast<double>(std::fabs(value - out.q.at(a, v))));
          next.at(a, v) = value;
        }
      }
      change[s] = largest;
    });
    std::swap(out.q, next);
    ++out.sweeps;
    out.change = change.empty() ? 0 : *std::max_element(change.begin(), change.end());
    if (out.change < tolerance) break;
  }
  return out;
}

double meanAdvantageOver(const QTable& best, const QTable& values, const QTable& policy) {
  if (best.vertexCount() != values.vertexCount() || best.vertexCount() != policy.vertexCount() ||
      best.actionCount() != values.actionCount() || best.actionCount() != policy.actionCount())
    throw Error(
        fmt::format("best-response gap: expected three tables of one layout, found {} x {}, {} x {} and {} x {} "
                    "(actions x vertices)",
                    best.actionCount(), best.vertexCount(), values.actionCount(), values.vertexCount(),
                    policy.actionCount(), policy.vertexCount()));
  double sum = 0;
  std::size_t pairs = 0;
  for (std::size_t s = 0; s < best.stateCount(); ++s) {
    const std::size_t n = best.actionsOf(s);
    if (n == 0) continue;
    for (std::size_t v = 0; v < best.vertexCount(); ++v) {
      const float* b = best.row(s, v);
      const float* p = policy.row(s, v);
      const std::size_t pick = static_cast<std::size_t>(std::max_element(p, p + n) - p);  // ties: the lowest index
      sum += static_cast<double>(*std::max_element(b, b + n)) - values.row(s, v)[pick];
      ++pairs;
    }
  }
  return pairs > 0 ? sum / static_cast<double>(pairs) : 0;
}

}  // namespace mgrl
