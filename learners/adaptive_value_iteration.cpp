// adaptive_value_iteration: variable resolution after R. Munos and A. Moore, "Variable
// resolution discretization in optimal control", Machine Learning 49 (2002). Their
// top-down scheme: start from a coarse kd-trie, solve the discrete problem on it, split the
// cells a splitting criterion ranks highest ("with some rate"), re-solve, repeat. Of their
// criteria this implements the local ones (the section "splitting methods based on local
// considerations"): value non-linearity (the backup at a cell's centre against the value
// interpolated there from its corners), policy disagreement (the corners' greedy actions
// differ) and the combination of the two; and their non-local influence x standard
// deviation criterion (influenceField below). On a kd_tree with refinement: conforming a
// split also splits neighbours, so a round's vertex count is checked after refining (see
// train()). Interpolation is multilinear in the kd_tree's boxes, not their Kuhn
// triangulation, so that the runtime controller interpolates as it does on the fixed grids.
//
// Each solve is value_iteration's (the same framework sweep and backup), warm-started from
// the previous tree's solution interpolated onto the new vertices. Nothing is random: the
// same problem and parameters give the same tree and table.
//
// Why one file of about 650 lines: the refinement loop, the splitting criteria and the
// influence field are one algorithm from one paper, and the criteria are private to it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "learners.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/random.hpp"

namespace mgrl::learners {

namespace {

// Targets at which backupGap() compares starts: this many uniform in the grid's
// coordinates (a fixed seed), and at most kGapVertexPoints of the starts' final vertices.
constexpr std::size_t kGapPoints = 200, kGapVertexPoints = 400;
constexpr std::uint64_t kGapSeed = 7;

// The influence and variance fixed points stop at this relative change or sweep count.
constexpr double kInfluenceTolerance = 1e-4;
constexpr int kInfluenceSweeps = 2000;

struct LeafScores {
  std::vector<double> value;   // mean over motion states of |backup - interpolation| at the centre
  std::vector<double> policy;  // fraction of motion states whose corners disagree on the action
  // Sum over motion states of the largest influence x standard deviation at a free corner
  // (influence_policy: only the states whose corners disagree); empty unless asked for.
  std::vector<double> influence;
};

// Influence and standard deviation at every (motion state, vertex), index s * V + v.
struct InfluenceField {
  std::vector<double> influence, deviation;
  int sweeps = 0;
};

// V_s at target e by one backup: the best over s's out-actions of the reward plus the
// discounted value interpolated where the target lands (0 outside the grid).
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

// A reference-free error of a solution, to rank starts: the root mean square over motion
// states and `points` of V_s by one backup at the target against V_s interpolated there
// (the value criterion's measure, Munos & Moore's value non-linearity, taken at given
// targets instead of cell centres), and the root mean square of V_s itself there.
// Deterministic whatever the thread count.
struct Gap {
  double gap = 0, value = 0;
  // The gap relative to the value: +infinity for a solution that is 0 at every target.
  double relative() const { return value > 0 ? gap / value : std::numeric_limits<double>::infinity(); }
};
Gap backupGap(const Problem& problem, const Discretizer& grid, const GridModel& g, const QTable& q,
              const std::vector<Eigen::Vector3d>& points, unsigned threads) {
  const std::size_t states = q.stateCount();
  std::size_t widest = 0;
  for (std::size_t s = 0; s < states; ++s) widest = std::max(widest, q.actionsOf(s));
  std::vector<double> squares(states, 0.0), values(states, 0.0), counts(states, 0.0);
  parallelFor(states, threads, [&](std::size_t s, unsigned) {
    const std::size_t n = q.actionsOf(s);
    if (n == 0) return;
    std::vector<float> sum(widest + QTable::kPadding);
    for (const Eigen::Vector3d& e : points) {
      GridCell cell;
      if (!grid.locate(e, cell)) continue;
      std::fill(sum.begin(), sum.end(), 0.0f);
      addInterpolated(sum.data(), q, static_cast<std::uint32_t>(s), grid.stencil(cell), 1.0f);
      const double here = *std::max_element(sum.begin(), sum.begin() + static_cast<std::ptrdiff_t>(n));
      const double backedUp = backedUpValue(problem, grid, g, q, s, e);
      squares[s] += (backedUp - here) * (backedUp - here);
      values[s] += here * here;
      counts[s] += 1;
    }
  });
  double total = 0, value = 0, count = 0;
  for (std::size_t s = 0; s < states; ++s) {
    total += squares[s];
    value += values[s];
    count += counts[s];
  }
  if (count == 0) return {};
  return {std::sqrt(total / count), std::sqrt(value / count)};
}

class AdaptiveValueIteration final : public Learner {
 public:
  explicit AdaptiveValueIteration(const Params& p)
      : maxVertices_(static_cast<std::size_t>(p.integer("max_vertices"))),
        maxRounds_(static_cast<int>(p.integer("max_rounds"))),
        splitFraction_(p.number("split_fraction")),
        splitTolerance_(p.number("split_tolerance")),
        criterion_(p.choice("criterion")),
        countFree_(p.choice("count_vertices") == "free"),
        tolerance_(p.number("tolerance")),
        maxSweeps_(static_cast<std::uint64_t>(p.integer("max_sweeps"))),
        starts_(static_cast<std::size_t>(p.integer("starts"))),
        startStep_(p.number("start_step")),
        threads_(static_cast<unsigned>(p.integer("threads"))) {}

  std::string type() const override { return "adaptive_value_iteration"; }
  void checkGrid(const Discretizer& grid) const override {
    if (!grid.refinable())
      throw Error(fmt::format("adaptive_value_iteration: expected a discretizer that can be refined (type kd_tree), "
                              "found {}",
                              grid.type()));
  }

  TrainResult train(const TrainContext& context) const override;
  // The last round's tree: max_vertices rows (count_vertices: all). Counting free vertices
  // only, the tied ones take rows too; up to about as many again was measured (55-65 % tied
  // with refinement: local), so twice the budget.
  std::size_t trainingVertices(const Discretizer& grid) const override {
    return std::max(grid.vertexCount(), countFree_ ? 2 * maxVertices_ : maxVertices_);
  }
  // Every start's table is kept until the gaps are measured.
  std::size_t extraTables() const override { return starts_ - 1; }

 private:
  LeafScores score(const Problem& problem, const Discretizer& grid, const GridModel& g, const QTable& q,
                   unsigned threads) const;
  std::vector<std::uint32_t> choose(const Discretizer& grid, const LeafScores& scores) const;
  // The vertices counted against max_vertices: all of them (table rows) or the free ones.
  std::size_t counted(const Discretizer& grid) const {
    return countFree_ ? grid.vertexCount() - grid.hanging().size() : grid.vertexCount();
  }

  // The initial cells of each start: the grid's own, then scaled by 1 - i start_step
  // (rounded, at least 1; shapes already listed are skipped).
  std::vector<std::vector<long long>> startShapes(const Discretizer& grid) const {
    std::vector<std::vector<long long>> out{grid.initialCells()};
    for (int i = 1; out.size() < starts_ && 1 - i * startStep_ > 0; ++i) {
      std::vector<long long> cells;
      for (long long n : out[0])
        cells.push_back(std::max(1LL, std::llround((1 - i * startStep_) * static_cast<double>(n))));
      if (std::find(out.begin(), out.end(), cells) == out.end()) out.push_back(std::move(cells));
    }
    return out;
  }

  std::size_t maxVertices_;
  int maxRounds_;
  double splitFraction_, splitTolerance_;
  std::string criterion_;
  bool countFree_;
  double tolerance_;
  std::uint64_t maxSweeps_;
  std::size_t starts_;
  double startStep_;
  unsigned threads_;
};

// Q of `from` interpolated at every vertex of `to` (the warm start of the next solve).
QTable interpolated(const QTable& from, const Discretizer& fromGrid, const Discretizer& toGrid,
                    const StateActionModel& model, unsigned threads) {
  QTable to(model, toGrid.vertexCount());
  const std::size_t states = from.stateCount();
  std::size_t widest = 0;
  for (std::size_t s = 0; s < states; ++s) widest = std::max(widest, from.actionsOf(s));
  std::vector<Stencil> stencils(toGrid.vertexCount());
  for (std::size_t v = 0; v < toGrid.vertexCount(); ++v)
    stencils[v] = fromGrid.stencil(fromGrid.locateClamped(toGrid.vertexPosition(v)));
  parallelFor(states, threads, [&](std::size_t s, unsigned) {
    std::vector<float> sum(widest + QTable::kPadding);
    const std::size_t n = from.actionsOf(s);
    for (std::size_t v = 0; v < toGrid.vertexCount(); ++v) {
      std::fill(sum.begin(), sum.end(), 0.0f);
      addInterpolated(sum.data(), from, static_cast<std::uint32_t>(s), stencils[v], 1.0f);
      std::copy(sum.begin(), sum.begin() + static_cast<std::ptrdiff_t>(n), to.row(s, v));
    }
  });
  return to;
}

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
        if (k == 0) first = best;
        else differ = differ || best != first;
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
      room, std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(splitFraction_ * static_cast<double>(leaves)))));
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
  const std::vector<std::uint32_t> byValue = criterion_ == "policy" ? std::vector<std::uint32_t>{}
                                                                      : ranked(scores.value, splitTolerance_);
  const std::vector<std::uint32_t> byPolicy = criterion_ == "value" ? std::vector<std::uint32_t>{}
                                                                      : ranked(scores.policy, 0.0);
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

TrainResult AdaptiveValueIteration::train(const TrainContext& context) const {
  const Problem& problem = context.problem;
  const unsigned threads = threads_ > 0 ? threads_ : context.threads;
  TrainingClock clock;  // snapshots (TrainObserver::snapshot) are not training
  checkGrid(problem.grid);
  if (counted(problem.grid) > maxVertices_)
    throw Error(fmt::format("adaptive_value_iteration: max_vertices: expected at least the initial tree's {} "
                            "{}vertices, found {}",
                            counted(problem.grid), countFree_ ? "free " : "", maxVertices_));

  // One refinement from an initial tree: solve, split, solve again, up to the budget.
  struct Run {
    QTable q;
    std::shared_ptr<const Discretizer> owned;  // the final tree if it is not problem.grid
    const Discretizer* grid = nullptr;
    nlohmann::json rounds = nlohmann::json::array();
    std::string stopped = "max_rounds";
    std::uint64_t sweeps = 0;
    double change = 0, residual = 0;
    Gap gap;
  };
  TrainResult result;
  std::uint64_t updates = 0;
  std::vector<float> stage;
  // `initial` is problem.grid (with its tabulated context.grid) or a restarted copy of it.
  auto refine = [&](std::shared_ptr<const Discretizer> restart) {
    Run run;
    run.owned = std::move(restart);
    run.grid = run.owned ? run.owned.get() : &problem.grid;
    QTable& q = run.q;
    q = QTable(problem.model, run.grid->vertexCount());
    QTable next;
    for (int round = 0;; ++round) {
      GridModel built;
      const bool given = round == 0 && !run.owned;
      if (!given) built = GridModel::build({problem.model, *run.grid, problem.reward, problem.environment}, threads);
      const GridModel& g = given ? context.grid : built;
      // Value iteration on the current tree (value_iteration's Jacobi sweeps).
      next = q;
      const std::uint64_t pairs = static_cast<std::uint64_t>(g.vertexCount) * g.actionCount;
      std::uint64_t sweeps = 0;
      while (sweeps < maxSweeps_) {
        run.change = sweep(q, next, g, threads, stage);
        std::swap(q, next);
        ++sweeps;
        updates += pairs;
        result.curve.push_back({updates, clock.seconds(), run.change, 0});
        if (context.observer) context.observer->progress({updates, 0, clock.seconds(), run.change});
        if (context.stop && context.stop->load(std::memory_order_relaxed) && run.change >= tolerance_)
          throw TrainInterrupted(updates, 0, false);
        if (run.change < tolerance_) break;
      }
      run.sweeps += sweeps;
      if (snapshotsWanted(context.observer) > 0)  // one per round: the values converged on this tree
        takeSnapshot(*context.observer, clock, q, result.curve.back(), run.grid == &problem.grid ? nullptr : run.grid);
      nlohmann::json record = {{"vertices", run.grid->vertexCount()},
                               {"free_vertices", run.grid->vertexCount() - run.grid->hanging().size()},
                               {"leaves", run.grid->cellCount()},
                               {"hanging_vertices", run.grid->hanging().size()},
                               {"sweeps", sweeps},
                               {"last_change", run.change}};
      // The end of this run: its residual, and with several starts the error that ranks them.
      auto finish = [&] { run.residual = bellmanResidual(q, g, threads).max; };
      if (counted(*run.grid) >= maxVertices_) run.stopped = "max_vertices";
      if (round >= maxRounds_) run.stopped = "max_rounds";
      if (counted(*run.grid) >= maxVertices_ || round >= maxRounds_) {
        run.rounds.push_back(record);
        finish();
        break;
      }
      const LeafScores scores = score(problem, *run.grid, g, q, threads);
      record["largest_value_gap"] = *std::max_element(scores.value.begin(), scores.value.end());
      record["largest_policy_disagreement"] = *std::max_element(scores.policy.begin(), scores.policy.end());
      if (!scores.influence.empty())
        record["largest_influence_deviation"] = *std::max_element(scores.influence.begin(), scores.influence.end());
      std::vector<std::uint32_t> splits = choose(*run.grid, scores);
      // A conforming kd_tree splits neighbours too, so a split may add more vertices than
      // choose() assumed: keep the longest prefix of the ranking that fits the budget.
      std::shared_ptr<const Discretizer> refined;
      bool budgetSpent = false;
      if (!splits.empty()) refined = run.grid->refined(splits);
      if (refined && counted(*refined) > maxVertices_) {
        std::size_t fits = 0, over = splits.size();
        std::shared_ptr<const Discretizer> best;
        while (over - fits > 1) {
          const std::size_t mid = (fits + over) / 2;
          std::shared_ptr<const Discretizer> trial = run.grid->refined({splits.begin(), splits.begin() + mid});
          if (counted(*trial) <= maxVertices_) {
            fits = mid;
            best = std::move(trial);
          } else {
            over = mid;
          }
        }
        splits.resize(fits);
        refined = std::move(best);
        budgetSpent = splits.empty();
      }
      record["splits"] = splits.size();
      run.rounds.push_back(record);
      if (splits.empty()) {
        // Every leaf is within the tolerance, at the depth limit, or the budget is spent.
        run.stopped = budgetSpent || counted(*run.grid) + (std::size_t{1} << (run.grid->dimension() - 1)) > maxVertices_
                          ? "max_vertices"
                          : "tolerance";
        finish();
        break;
      }
      q = interpolated(q, *run.grid, *refined, problem.model, threads);
      run.owned = std::move(refined);
      run.grid = run.owned.get();
    }
    return run;
  };

  // The starts (`starts`): the scenario's initial cells, then each scaled down by
  // start_step more; each refined to the budget, the lowest backup gap relative to the
  // value kept (ties: the earlier start). Every start is measured at the same targets:
  // random ones, and vertices of every start's final tree. Relative, because a start whose
  // vertices all missed a sparse reward has a flat value of 0 and hence almost no gap; it
  // has no value either, and ranks last.
  const std::vector<std::vector<long long>> shapes = startShapes(problem.grid);
  nlohmann::json tried = nlohmann::json::array();
  std::vector<Run> runs;
  std::vector<std::size_t> triedIndex;
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    std::shared_ptr<const Discretizer> restart;
    if (i > 0) {
      try {
        restart = problem.grid.withInitialCells(shapes[i]);
      } catch (const Error& e) {  // e.g. more initial splits than max_depth allows
        tried.push_back({{"initial_cells", shapes[i]}, {"skipped", e.what()}});
        continue;
      }
    }
    if (context.observer && shapes.size() > 1)
      context.observer->note(fmt::format("start {} of {}: {} initial cells", i + 1, shapes.size(),
                                         fmt::join(shapes[i], "x")));
    runs.push_back(refine(std::move(restart)));
    const Run& run = runs.back();
    triedIndex.push_back(tried.size());
    tried.push_back({{"initial_cells", shapes[i]},
                     {"vertices", run.grid->vertexCount()},
                     {"rounds", run.rounds.size()},
                     {"stopped_by", run.stopped}});
  }
  std::size_t chosen = 0;
  if (runs.size() > 1) {
    std::vector<Eigen::Vector3d> points;
    Rng rng(kGapSeed);
    for (std::size_t i = 0; i < kGapPoints; ++i) {
      const std::array<double, 4> u{rng.uniform(), rng.uniform(), rng.uniform(), 0};
      points.push_back(problem.grid.sample(u).position);  // kd_tree grids have no speed layers
    }
    std::size_t vertices = 0;
    for (const Run& run : runs) vertices += run.grid->vertexCount();
    const std::size_t every = (vertices + kGapVertexPoints - 1) / kGapVertexPoints;
    std::size_t k = 0;
    for (const Run& run : runs)
      for (std::size_t v = 0; v < run.grid->vertexCount(); ++v, ++k)
        if (k % every == 0) points.push_back(run.grid->vertexPosition(v));
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const Problem on{problem.model, *runs[i].grid, problem.reward, problem.environment};
      runs[i].gap = backupGap(on, *runs[i].grid, GridModel::frame(on), runs[i].q, points, threads);
      nlohmann::json& entry = tried[triedIndex[i]];
      entry["backup_gap"] = runs[i].gap.gap;
      entry["value_rms"] = runs[i].gap.value;
      entry["relative_gap"] = std::isfinite(runs[i].gap.relative()) ? nlohmann::json(runs[i].gap.relative()) : nlohmann::json();
      if (runs[i].gap.relative() < runs[chosen].gap.relative()) chosen = i;
    }
  }
  if (context.observer && runs.size() > 1)
    context.observer->note(fmt::format("kept the start from {} initial cells (relative backup gap {:.4g}, of {} "
                                       "starts)",
                                       fmt::join(runs[chosen].grid->initialCells(), "x"), runs[chosen].gap.relative(),
                                       runs.size()));
  Run best = std::move(runs[chosen]);
  const nlohmann::json chosenCells = tried[triedIndex[chosen]].at("initial_cells");
  result.finalResidual = best.residual;
  result.table = std::move(best.q);
  result.grid = best.owned;
  result.updates = updates;
  result.seconds = clock.seconds();
  const Discretizer& grid = *best.grid;
  result.stats = {{"rounds", best.rounds},
                  {"stopped_by", best.stopped},
                  {"sweeps", best.sweeps},
                  {"vertices", grid.vertexCount()},
                  {"free_vertices", grid.vertexCount() - grid.hanging().size()},
                  {"table_bytes", result.table.bytes()},
                  {"leaves", grid.cellCount()},
                  {"hanging_vertices", grid.hanging().size()},
                  {"last_change", best.change},
                  {"initial_cells", chosenCells}};
  if (shapes.size() > 1) result.stats["starts"] = tried;
  return result;
}

}  // namespace

void registerAdaptiveValueIteration(LearnerRegistry& registry) {
  registry.add(
      {"adaptive_value_iteration",
       "value iteration on a kd_tree grid that splits the cells where the value is not linear or the corners' "
       "greedy actions disagree, and solves again, up to a vertex budget (Munos & Moore 2002)",
       {ParamSpec::integer("max_vertices", 4000, 1, static_cast<long long>(kMaxGridVertices), "vertices",
                           "vertex budget (see count_vertices): no refinement past it (at least the initial tree's)"),
        ParamSpec::integer("max_rounds", 30, 0, 100000, "rounds", "give up refining after this many rounds"),
        ParamSpec::number("split_fraction", 0.1, 1e-6, 1, "", "split at most this fraction of the leaves per round"),
        ParamSpec::number("split_tolerance", 1e-3, 0, 1e9, "",
                          "value criterion: split only leaves whose mean value gap is above this"),
        ParamSpec::choice("criterion", "both", {"value", "policy", "both", "influence", "influence_policy"},
                          "value: value non-linearity; policy: policy disagreement between corners; both: the two "
                          "rankings in turn; influence: influence x standard deviation (Munos & Moore's stdev_inf); "
                          "influence_policy: influence x standard deviation over the states whose corners disagree"),
        ParamSpec::choice("count_vertices", "all", {"all", "free"},
                          "what max_vertices counts: all: every vertex (the table's rows); free: only vertices not "
                          "tied to a coarser face (the table still holds a row for each tied one)"),
        ParamSpec::number("tolerance", 1e-4, 1e-9, 1, "", "each solve stops when no value changes more than this"),
        ParamSpec::integer("max_sweeps", 1000, 1, 1'000'000, "sweeps", "each solve gives up after this many sweeps"),
        ParamSpec::integer("starts", 1, 1, 8, "trees",
                           "refine from this many initial trees (the discretizer's initial cells, then scaled down "
                           "by start_step each) and keep the one with the lowest backup gap at 200 fixed random "
                           "targets; training takes about as many times longer"),
        ParamSpec::number("start_step", 0.1, 0.01, 0.5, "",
                          "starts: each further start's initial cells are the first's times 1 - i x start_step"),
        threadsSpec()},
       [](const Params& p) { return std::make_unique<AdaptiveValueIteration>(p); },
       {},
       nullptr,
       "{type: adaptive_value_iteration, max_vertices: 60, max_rounds: 3}"});  // the conformance suite's
}

}  // namespace mgrl::learners
