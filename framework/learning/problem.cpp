#include "mgrl/learning/problem.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/learning/learner.hpp"

namespace mgrl {

std::size_t GridModel::bytes() const {
  return corners.size() * 4 + transition.size() * sizeof(GridTransition) + reward.size() * sizeof(float) +
         vertexState.size() * sizeof(TargetState) + discount.size() * 4 + rigid.size() * 8 +
         actionTo.size() * 4 + incomingBegin.size() * 4 + incoming.size() * 4;
}

double GridModel::trainingBytes(std::size_t actions, std::size_t vertices, bool compact) {
  const double pairs = static_cast<double>(actions) * static_cast<double>(vertices);
  const double model = compact ? sizeof(float) : sizeof(GridTransition);
  return pairs * (model + sizeof(std::uint32_t) + 2 * sizeof(float)) +
         static_cast<double>(vertices) * (8 * sizeof(std::uint32_t) + sizeof(TargetState)) +
         static_cast<double>(actions) * 16;
}

namespace {

// The lists of actions by end state, which sweeps go by.
void addIncoming(GridModel& g, const StateActionModel& m) {
  const std::size_t states = m.stateCount();
  g.incomingBegin.assign(states + 1, 0);
  for (std::uint32_t to : m.actionTo) ++g.incomingBegin[to + 1];
  for (std::size_t s = 0; s < states; ++s) g.incomingBegin[s + 1] += g.incomingBegin[s];
  g.incoming.resize(g.actionCount);
  std::vector<std::uint32_t> fill(g.incomingBegin.begin(), g.incomingBegin.end() - 1);
  for (std::size_t a = 0; a < g.actionCount; ++a) g.incoming[fill[m.actionTo[a]]++] = static_cast<std::uint32_t>(a);
}

}  // namespace

GridModel GridModel::frame(const Problem& problem) {
  const StateActionModel& m = problem.model;
  const Discretizer& grid = problem.grid;
  GridModel g;
  g.vertexCount = grid.vertexCount();
  g.actionCount = m.actionCount();
  g.dimension = grid.dimension();
  g.corners = grid.cellCorners();
  g.hanging = grid.hanging();
  g.actionTo = m.actionTo;
  g.stateActionBegin = m.stateActionBegin;
  g.discount.resize(g.actionCount);
  const double gamma = problem.reward.gamma();
  for (std::size_t a = 0; a < g.actionCount; ++a)
    g.discount[a] = static_cast<float>(std::pow(gamma, static_cast<double>(m.actionLength(a))));

  if (problem.environment.as<RigidTarget>()) {
    g.rigid.resize(4 * g.actionCount);
    for (std::size_t a = 0; a < g.actionCount; ++a) {
      const GroundMotion d = m.displacement(a);
      g.rigid[4 * a] = std::cos(d.dyaw);
      g.rigid[4 * a + 1] = std::sin(d.dyaw);
      g.rigid[4 * a + 2] = d.dx;
      g.rigid[4 * a + 3] = d.dz;
    }
  }
  addIncoming(g, m);
  return g;
}

void setLanding(GridTransition& t, const GridCell& cell) {
  if (cell.layerFrac != 0)
    throw Error(fmt::format("a backup's target landed between speed layers (fraction {}): the environment model must "
                            "keep the target's speed on a grid with speed layers",
                            cell.layerFrac));
  t.cell = static_cast<std::int32_t>(cell.cell);
  for (int k = 0; k < 3; ++k) t.frac[k] = cell.frac[k];
}

GridTransition tabulate(const Problem& problem, std::size_t a, const TargetState& vertex) {
  GridTransition t;
  t.reward = static_cast<float>(problem.reward.evaluate(problem.model, a, vertex));
  GridCell cell;
  if (problem.grid.locate(problem.environment.next(problem.model, a, vertex), cell)) setLanding(t, cell);
  return t;
}

namespace {

// f(a) for every action, in chunks over `threads` threads; once `stop` (may be null) is
// set, the chunks left are skipped and TrainInterrupted is thrown.
template <class F>
void forEachPair(std::size_t actions, unsigned threads, const std::atomic<bool>* stop, F f) {
  constexpr std::size_t kChunk = 64;
  parallelFor((actions + kChunk - 1) / kChunk, threads, [&](std::size_t chunk, unsigned) {
    if (stop && stop->load(std::memory_order_relaxed)) return;
    const std::size_t end = std::min(actions, (chunk + 1) * kChunk);
    for (std::size_t a = chunk * kChunk; a < end; ++a) f(a);
  });
  if (stop && stop->load()) throw TrainInterrupted(0, 0, false);
}

}  // namespace

GridModel GridModel::build(const Problem& problem, unsigned threads, const std::atomic<bool>* stop) {
  GridModel g = frame(problem);
  g.transition.assign(g.vertexCount * g.actionCount, GridTransition{});
  std::vector<TargetState> vertex(g.vertexCount);
  for (std::size_t v = 0; v < g.vertexCount; ++v) vertex[v] = problem.grid.vertexState(v);
  forEachPair(g.actionCount, threads, stop, [&](std::size_t a) {
    for (std::size_t v = 0; v < g.vertexCount; ++v)
      g.transition[a * g.vertexCount + v] = tabulate(problem, a, vertex[v]);
  });
  return g;
}

GridModel GridModel::buildCompact(const Problem& problem, unsigned threads, const std::atomic<bool>* stop) {
  GridModel g = frame(problem);
  g.vertexState.resize(g.vertexCount);
  for (std::size_t v = 0; v < g.vertexCount; ++v) g.vertexState[v] = problem.grid.vertexState(v);
  g.reward.assign(g.vertexCount * g.actionCount, 0.0f);
  forEachPair(g.actionCount, threads, stop, [&](std::size_t a) {
    for (std::size_t v = 0; v < g.vertexCount; ++v)
      g.reward[a * g.vertexCount + v] = static_cast<float>(problem.reward.evaluate(problem.model, a, g.vertexState[v]));
  });
  g.landingGrid = &problem.grid;
  g.landingEnvironment = &problem.environment;
  g.landingModel = &problem.model;
  return g;
}

GridTransition GridModel::moved(std::size_t a, std::size_t v) const {
  // tabulate() without the reward.
  GridTransition t;
  GridCell cell;
  const TargetState& e = vertexState[v];
  if (landingGrid->locate(rigid.empty() ? landingEnvironment->next(*landingModel, a, e) : rigidNext(a, e), cell))
    setLanding(t, cell);
  return t;
}

namespace {

// 16 lanes: one AVX-512 register, two AVX2 ones, four SSE ones, depending on the clone.
constexpr int kLanes = 16;
typedef float FloatV __attribute__((vector_size(4 * kLanes)));
typedef int IntV __attribute__((vector_size(4 * kLanes)));

inline FloatV loadV(const float* p) {
  FloatV v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

// sum_k weight[k] rows[k][j .. j + kLanes), added as a balanced tree: a short dependency
// chain, and the same order in every lane and every clone.
template <int K>
inline __attribute__((always_inline)) FloatV weightedSum(const float* const* rows, const FloatV* weight, std::uint32_t j) {
  FloatV term[K];
  for (int k = 0; k < K; ++k) term[k] = weight[k] * loadV(rows[k] + j);
  for (int width = K / 2; width >= 1; width /= 2)
    for (int k = 0; k < width; ++k) term[k] = term[2 * k] + term[2 * k + 1];
  return term[0];
}

// max_j sum_k w[k] rows[k][j] over j < n. Rows may be read up to kLanes - 1 floats past n
// (the table is padded); those lanes are masked out. The sum for each j is formed in the
// same order whatever the lane, so the result does not depend on n's remainder or the clone.
template <int K>
inline __attribute__((always_inline)) float maxWeightedRows(const float* const* rows, const float* w, std::uint32_t n) {
  const FloatV minusInf = FloatV{} - std::numeric_limits<float>::infinity();
  FloatV best = minusInf;
  FloatV weight[K];
  for (int k = 0; k < K; ++k) weight[k] = FloatV{} + w[k];
  std::uint32_t j = 0;
  for (; j + kLanes <= n; j += kLanes) {
    const FloatV acc = weightedSum<K>(rows, weight, j);
    best = acc > best ? acc : best;
  }
  if (j < n) {
    FloatV acc = weightedSum<K>(rows, weight, j);
    IntV lane;
    for (int i = 0; i < kLanes; ++i) lane[i] = i;
    lane += static_cast<int>(j);
    acc = lane < static_cast<int>(n) ? acc : minusInf;
    best = acc > best ? acc : best;
  }
  float result = best[0];
  for (int i = 1; i < kLanes; ++i) result = best[i] > result ? best[i] : result;
  return result;
}

__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
float maxRows4(const float* const* rows, const float* w, std::uint32_t n) {
  return maxWeightedRows<4>(rows, w, n);
}

__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
float maxRows8(const float* const* rows, const float* w, std::uint32_t n) {
  return maxWeightedRows<8>(rows, w, n);
}

template <int K>
inline __attribute__((always_inline)) void addWeightedRows(float* sum, const float* const* rows, const float* w,
                                                           std::uint32_t n) {
  FloatV weight[K];
  for (int k = 0; k < K; ++k) weight[k] = FloatV{} + w[k];
  for (std::uint32_t j = 0; j < n; j += kLanes) {
    FloatV acc = loadV(sum + j);
    for (int k = 0; k < K; ++k) acc += weight[k] * loadV(rows[k] + j);
    __builtin_memcpy(sum + j, &acc, sizeof acc);
  }
}

__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
void addRows4(float* sum, const float* const* rows, const float* w, std::uint32_t n) {
  addWeightedRows<4>(sum, rows, w, n);
}

__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
void addRows8(float* sum, const float* const* rows, const float* w, std::uint32_t n) {
  addWeightedRows<8>(sum, rows, w, n);
}

}  // namespace

std::size_t greedyAction(const StateActionModel& m, const Discretizer& grid, const QTable& q, std::uint32_t s,
                         const TargetState& e) {
  const std::uint32_t begin = m.stateActionBegin[s], n = m.stateActionBegin[s + 1] - begin;
  thread_local std::vector<float> scores;
  scores.assign(n + 16, 0.0f);  // vector code writes whole 16-float registers
  addInterpolated(scores.data(), q, s, grid.stencil(grid.locateClamped(e)), 1.0f);
  std::uint32_t best = 0;
  for (std::uint32_t j = 1; j < n; ++j)
    if (scores[j] > scores[best]) best = j;
  return begin + best;
}

void addInterpolated(float* sum, const QTable& q, std::uint32_t s, const Stencil& stencil, float scale) {
  const std::uint32_t n = static_cast<std::uint32_t>(q.actionsOf(s));
  const float* rows[16];
  float w[16];
  const int size = stencil.size <= 4 ? 4 : stencil.size <= 8 ? 8 : 16;
  for (int k = 0; k < size; ++k) {
    const int from = k < stencil.size ? k : 0;
    rows[k] = q.row(s, stencil.vertex[from]);
    w[k] = k < stencil.size ? scale * stencil.weight[k] : 0.0f;
  }
  if (size == 4) {
    addRows4(sum, rows, w, n);
  } else {
    addRows8(sum, rows, w, n);
    if (size == 16) addRows8(sum, rows + 8, w + 8, n);  // the upper speed layer
  }
}

float maxInterpolated(const QTable& q, const GridModel& g, std::uint32_t s, std::uint32_t cell, const float* frac) {
  const int d = g.dimension;
  const auto n = static_cast<std::uint32_t>(q.actionsOf(s));
  const float* block = q.row(s, 0);  // vertex v's row starts at block + v * n
  const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(cell) << d];
  const float* rows[8];
  if (d == 3) {
    // The products in cornerWeights' order, written out.
    const float f0 = frac[0], f1 = frac[1], f2 = frac[2], g0 = 1 - f0, g1 = 1 - f1, g2 = 1 - f2;
    const float w[8] = {g0 * g1 * g2, f0 * g1 * g2, g0 * f1 * g2, f0 * f1 * g2,
                        g0 * g1 * f2, f0 * g1 * f2, g0 * f1 * f2, f0 * f1 * f2};
    for (int k = 0; k < 8; ++k) rows[k] = block + static_cast<std::size_t>(corner[k]) * n;
    return maxRows8(rows, w, n);
  }
  float w[8];
  std::array<float, 3> f{frac[0], frac[1], frac[2]};
  cornerWeights(d, f, w);
  if (d == 2) {
    for (int k = 0; k < 4; ++k) rows[k] = block + static_cast<std::size_t>(corner[k]) * n;
    return maxRows4(rows, w, n);
  }
  // 1-D grids: two corners, padded with zero weights.
  for (int k = 0; k < 4; ++k) {
    rows[k] = block + static_cast<std::size_t>(corner[k & 1]) * n;
    if (k >= 2) w[k] = 0;
  }
  return maxRows4(rows, w, n);
}

double sweep(const QTable& in, QTable& out, const GridModel& g, unsigned threads) {
  std::vector<float> stage;
  return sweep(in, out, g, threads, stage);
}

double sweep(const QTable& in, QTable& out, const GridModel& g, unsigned threads, std::vector<float>& stage) {
  const std::size_t states = g.incomingBegin.size() - 1;
  const std::size_t V = g.vertexCount;
  const bool compact = g.compact();
  stage.resize(g.actionCount * V);
  // Backups grouped by end state: each group reads one block of `in` (its rows), which
  // stays in cache, and writes its actions' values contiguously into `stage` (a, v).
  parallelFor(states, threads, [&](std::size_t s, unsigned) {
    for (std::uint32_t i = g.incomingBegin[s]; i < g.incomingBegin[s + 1]; ++i) {
      const std::size_t a = g.incoming[i];
      float* values = &stage[a * V];
      // The kind of model tested once per action, not per backup (a sweep of a tabulated
      // model is a stream over its transitions).
      if (compact)
        for (std::size_t v = 0; v < V; ++v) values[v] = backup(in, g, a, g.landing(a, v));
      else
        for (std::size_t v = 0; v < V; ++v) values[v] = backup(in, g, a, g.transition[a * V + v]);
      // Hanging vertices keep to their coarse face (continuity across it), whatever their backup.
      g.hanging.apply(values);
    }
  });
  // Then into the state-major layout, block by block, measuring the change.
  const std::size_t sources = in.stateCount();
  std::vector<double> change(sources, 0.0);
  parallelFor(sources, threads, [&](std::size_t s, unsigned) {
    const std::size_t n = in.actionsOf(s);
    double largest = 0;
    const std::size_t begin = g.stateActionBegin[s];
    for (std::size_t v = 0; v < V; ++v) {
      const float* old = in.row(s, v);
      float* row = out.row(s, v);
      for (std::size_t j = 0; j < n; ++j) {
        const float value = stage[(begin + j) * V + v];
        largest = std::max(largest, static_cast<double>(std::fabs(value - old[j])));
        row[j] = value;
      }
    }
    change[s] = largest;
  });
  double largest = 0;
  for (double c : change) largest = std::max(largest, c);
  return largest;
}

Residual bellmanResidual(const QTable& q, const GridModel& g, unsigned threads, std::size_t stride) {
  stride = std::max<std::size_t>(1, stride);
  const std::size_t states = g.incomingBegin.size() - 1;
  std::vector<double> largest(states, 0.0), sum(states, 0.0);
  std::vector<std::size_t> pairs(states, 0);
  // A hanging vertex's value is an interpolation, not a fixed point of the backup.
  std::vector<std::uint8_t> tied(g.hanging.empty() ? 0 : g.vertexCount, 0);
  for (std::uint32_t v : g.hanging.vertex) tied[v] = 1;
  parallelFor(states, threads, [&](std::size_t s, unsigned) {
    for (std::uint32_t i = g.incomingBegin[s]; i < g.incomingBegin[s + 1]; ++i) {
      const std::size_t a = g.incoming[i];
      const std::size_t block = (g.vertexCount + stride - 1) / stride;
      const std::size_t first = (a % stride) * block, last = std::min(g.vertexCount, first + block);
      for (std::size_t v = first; v < last; ++v) {
        if (!tied.empty() && tied[v]) continue;
        const double r = std::fabs(static_cast<double>(backup(q, g, a, v)) - q.at(a, v));
        largest[s] = std::max(largest[s], r);
        sum[s] += r;
        ++pairs[s];
      }
    }
  });
  Residual result;
  std::size_t measured = 0;
  for (std::size_t s = 0; s < states; ++s) {
    result.max = std::max(result.max, largest[s]);
    result.mean += sum[s];
    measured += pairs[s];
  }
  if (measured > 0) result.mean /= static_cast<double>(measured);
  return result;
}

}  // namespace mgrl
