// q_learning: Lee & Lee 2004, sec. 4.2, as the paper states it. From a random pose (state)
// and a random target inside the grid, take uniformly random actions. After each action a
// with the target at e, update every grid vertex v of e's cell:
//     Q(v, a) += alpha (r(v, a) + gamma^t_a max_a' Q(e'_v, a') - Q(v, a)),
// where e'_v is v moved along by the action (the environment model) and Q(e'_v, .) is
// interpolated from e'_v's cell (0 when e'_v leaves the grid). Restart when the target
// itself leaves the grid (or, with max_episode_actions, after that many actions: an
// option beyond the paper for captures whose avatar hardly travels). alpha falls linearly
// from 1 over the budget of actions.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <thread>

#include <fmt/format.h>

#include "learners.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "q_learning_checkpoint.hpp"

namespace mgrl::learners {

namespace {

class QLearning final : public Learner {
 public:
  explicit QLearning(const Params& p)
      : budget_(static_cast<std::uint64_t>(p.integer("budget"))),
        seed_(static_cast<std::uint64_t>(p.integer("seed"))),
        alphaFinal_(p.number("alpha_final")),
        curvePoints_(static_cast<std::uint64_t>(p.integer("curve_points"))),
        checkpointEvery_(static_cast<std::uint64_t>(p.integer("checkpoint_every"))),
        curveSample_(static_cast<std::size_t>(p.integer("curve_sample"))),
        maxEpisode_(static_cast<std::uint64_t>(p.integer("max_episode_actions"))),
        threads_(static_cast<unsigned>(p.integer("threads"))) {}

  std::string type() const override { return "q_learning"; }
  bool takesCompactModel() const override { return true; }

  TrainResult train(const TrainContext& context) const override;

 private:
  std::uint64_t budget_, seed_;
  double alphaFinal_;
  std::uint64_t curvePoints_, checkpointEvery_;
  std::size_t curveSample_;  ///< a curve point's residual is measured on one (action, vertex) pair in this many
  std::uint64_t maxEpisode_;  ///< 0: the paper's rule (restart only when the target leaves)
  unsigned threads_;
};

TrainResult QLearning::train(const TrainContext& context) const {
  const StateActionModel& m = context.problem.model;
  const Discretizer& grid = context.problem.grid;
  const EnvironmentModel& environment = context.problem.environment;
  const GridModel& g = context.grid;
  const unsigned threads = threads_ > 0 ? threads_ : context.threads;
  const std::uint64_t total = budget_;
  // Its updates move vertices one by one; a hanging vertex must follow its coarse face.
  if (!g.hanging.empty())
    throw Error(fmt::format("q_learning: the {} grid has {} hanging vertices, which its updates cannot keep "
                            "continuous; use value_iteration or adaptive_value_iteration",
                            grid.type(), g.hanging.size()));

  TrainResult result;
  result.table = QTable(m, g.vertexCount);
  QTable& q = result.table;
  Walk walk;
  walk.rng = Rng(seed_);
  double secondsBefore = 0;

  auto restart = [&](Walk& w) {
    w.state = static_cast<std::uint32_t>(w.rng.below(m.stateCount()));
    do w.target = grid.sample(w.rng);
    while (!grid.inside(w.target));
    ++w.restarts;
    w.episodeActions = 0;
  };

  // Cells the walk has been in (those of the run it resumes included), for the coverage
  // report: the paper's rule can keep a walk in a few cells for its whole budget.
  std::vector<std::uint8_t> cellSeen(grid.cellCount(), 0);
  bool resumed = false;
  if (context.checkpointer) {
    // The checkpointer runs this before trusting the checkpoint: a state that fails it is
    // reported and ignored there, and the table left as it is (all zeros).
    Saved saved;
    const StateCheck check = [&](const nlohmann::json& state, const ManifestReader& reader) {
      saved = readSaved(state, reader, m.stateCount(), grid.cellCount(), total, curvePoints_, maxEpisode_);
    };
    if (context.checkpointer->loadChecked(q, check)) {
      walk = saved.walk;
      secondsBefore = saved.seconds;
      cellSeen = std::move(saved.cellSeen);
      result.curve = std::move(saved.curve);
      resumed = true;
    }
  }
  if (!resumed) restart(walk);

  TrainingClock clock(secondsBefore);  // snapshots are not training
  auto curveAt = [&](std::uint64_t i) { return total * i / curvePoints_; };
  std::uint64_t nextCurveIndex = 1;
  while (nextCurveIndex <= curvePoints_ && curveAt(nextCurveIndex) <= walk.updates) ++nextCurveIndex;
  // Snapshots for an observer that wants them, at budget * i / n; none before a resume point.
  const std::uint64_t snapshots = snapshotsWanted(context.observer);
  auto snapshotAt = [&](std::uint64_t i) { return total * i / snapshots; };
  std::uint64_t nextSnapshotIndex = 1;
  while (nextSnapshotIndex <= snapshots && snapshotAt(nextSnapshotIndex) <= walk.updates) ++nextSnapshotIndex;
  double lastResidual = result.curve.empty() ? -1 : result.curve.back().residual;

  constexpr std::uint64_t kProgressEvery = 1 << 16;
  const int d = g.dimension;
  const int corners = 1 << d;
  const bool rigid = !g.rigid.empty();
  struct Step {
    std::uint32_t action, cell;
  };
  std::vector<std::uint64_t> seen(g.vertexCount, 0);  // rows prefetched for the step at `stamp`
  std::uint64_t stamp = 0;
  const std::uint32_t* stateBegin = m.stateActionBegin.data();
  const double alphaSlope = (1 - alphaFinal_) / static_cast<double>(total);

  // The walk (states, targets, restarts, random actions) does not depend on Q, so it is
  // walked a chunk at a time, recording (action, cell) per step and consuming the random
  // numbers in the same order as interleaving would; the updates then follow the record.
  // Knowing the steps ahead lets the update loop prefetch (the tables are far bigger than
  // the caches and random actions defeat the hardware's own prefetching), and with two
  // threads the next chunk is walked while this one is updated. Chunks end at progress,
  // curve and checkpoint points, so the same seed gives the same table either way.
  // A compact model (GridModel::buildCompact) stores no transitions: the walk finds where
  // each step's corners land as it records the step, on its own thread when there are two,
  // and the updates read them in order instead of from a table (and the rewards, like Q,
  // from the model's table, prefetched).
  const bool compact = g.compact();
  auto walkChunk = [&](Walk& w, std::uint64_t stop, std::vector<Step>& steps, std::vector<GridTransition>& landed) {
    steps.clear();
    landed.clear();
    GridCell cell;
    if (!grid.locate(w.target, cell)) {  // only on the boundary's round-off
      restart(w);
      grid.locate(w.target, cell);
    }
    for (std::uint64_t k = w.updates; k < stop; ++k) {
      const std::uint32_t s = w.state;
      const std::size_t a = stateBegin[s] + static_cast<std::uint32_t>(w.rng.below(stateBegin[s + 1] - stateBegin[s]));
      steps.push_back({static_cast<std::uint32_t>(a), cell.cell});
      cellSeen[cell.cell] = 1;
      if (compact) {
        const std::uint32_t* c = &g.corners[static_cast<std::size_t>(cell.cell) << d];
        for (int j = 0; j < corners; ++j) landed.push_back(g.moved(a, c[j]));
      }
      w.target = rigid ? g.rigidNext(a, w.target) : environment.next(m, a, w.target);
      w.state = m.actionTo[a];
      ++w.episodeActions;
      // The paper restarts when the target leaves the grid (sec. 4.2); a cap on the
      // episode also restarts a walk whose avatar hardly travels, which would otherwise
      // keep the target in a few cells for the whole budget.
      if (!grid.locate(w.target, cell) || (maxEpisode_ > 0 && w.episodeActions >= maxEpisode_)) {
        restart(w);
        grid.locate(w.target, cell);
      }
    }
    w.updates = stop;
  };
  // Compiled once per kind of model (a std::bool_constant), so the tabulated loop carries
  // no test of the model's kind.
  auto update = [&](auto compactModel, const std::vector<Step>& steps, const std::vector<GridTransition>& landed,
                    std::uint64_t from) {
    constexpr bool kCompact = decltype(compactModel)::value;
    constexpr std::size_t kTransitionAhead = 6, kRowsAhead = 3;
    // Step i's corner j: from the table, or as the walk found it (compact models; the
    // reward is not needed there).
    auto transition = [&](std::size_t i, const std::uint32_t* c, int j) -> const GridTransition& {
      if constexpr (kCompact)
        return landed[i * static_cast<std::size_t>(corners) + static_cast<std::size_t>(j)];
      else
        return g.transition[steps[i].action * g.vertexCount + c[j]];
    };
    for (std::size_t i = 0; i < steps.size(); ++i) {
      if (i + kTransitionAhead < steps.size()) {
        const Step& ahead = steps[i + kTransitionAhead];
        const std::uint32_t* c = &g.corners[static_cast<std::size_t>(ahead.cell) << d];
        for (int j = 0; j < corners; ++j) {
          if constexpr (kCompact)
            __builtin_prefetch(&g.reward[ahead.action * g.vertexCount + c[j]]);
          else
            __builtin_prefetch(&g.transition[ahead.action * g.vertexCount + c[j]]);
          __builtin_prefetch(&q.at(ahead.action, c[j]), 1);
        }
      }
      if (i + kRowsAhead < steps.size()) {
        // The rows the backups of that step will interpolate: its transitions should be
        // in cache by now.
        const Step& ahead = steps[i + kRowsAhead];
        const std::uint32_t* c = &g.corners[static_cast<std::size_t>(ahead.cell) << d];
        const std::uint32_t to = g.actionTo[ahead.action];
        const std::size_t n = q.actionsOf(to);
        ++stamp;
        for (int j = 0; j < corners; ++j) {
          const GridTransition& t = transition(i + kRowsAhead, c, j);
          if (t.cell < 0) continue;
          const std::uint32_t* u = &g.corners[static_cast<std::size_t>(t.cell) << d];
          for (int l = 0; l < corners; ++l) {
            // The moved corners' cells overlap: each row once.
            if (seen[u[l]] == stamp) continue;
            seen[u[l]] = stamp;
            const float* row = q.row(to, u[l]);
            for (std::size_t o = 0; o < n; o += 16) __builtin_prefetch(row + o);
          }
        }
      }
      const std::size_t a = steps[i].action;
      const float alpha = static_cast<float>(1 - alphaSlope * static_cast<double>(from + i));
      const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(steps[i].cell) << d];
      for (int j = 0; j < corners; ++j) {
        const std::size_t v = corner[j];
        float target;
        if constexpr (kCompact) {
          GridTransition t = transition(i, corner, j);
          t.reward = g.reward[a * g.vertexCount + v];
          target = backup(q, g, a, t);
        } else {
          target = backup(q, g, a, transition(i, corner, j));
        }
        float& value = q.at(a, v);
        value += alpha * (target - value);
      }
    }
  };
  auto chunkEnd = [&](std::uint64_t from) {
    std::uint64_t stop = std::min(total, from + kProgressEvery);
    // The first curve point after `from`: curveAt rounds down, so look just past from's share.
    for (std::uint64_t i = std::max<std::uint64_t>(1, from * curvePoints_ / total); i <= curvePoints_; ++i)
      if (curveAt(i) > from) {
        stop = std::min(stop, curveAt(i));
        break;
      }
    // The same for snapshots: where chunks end does not change the table.
    for (std::uint64_t i = std::max<std::uint64_t>(1, snapshots > 0 ? from * snapshots / total : 1); i <= snapshots; ++i)
      if (snapshotAt(i) > from) {
        stop = std::min(stop, snapshotAt(i));
        break;
      }
    if (checkpointEvery_ > 0) stop = std::min(stop, (from / checkpointEvery_ + 1) * checkpointEvery_);
    return stop;
  };

  Walk ahead = walk;
  std::vector<Step> current, next;
  std::vector<GridTransition> currentLanded, nextLanded;
  current.reserve(kProgressEvery);
  next.reserve(kProgressEvery);
  if (walk.updates < total) walkChunk(ahead, chunkEnd(walk.updates), current, currentLanded);
  while (walk.updates < total) {
    const std::uint64_t from = walk.updates;
    const Walk atStop = ahead;  // the walk as it stands when this chunk's updates are done
    const std::uint64_t stop = atStop.updates;
    std::thread walker;
    if (stop < total) {
      const std::uint64_t nextStop = chunkEnd(stop);
      if (threads > 1)
        walker = std::thread([&, nextStop] { walkChunk(ahead, nextStop, next, nextLanded); });
      else
        walkChunk(ahead, nextStop, next, nextLanded);
    }
    try {
      if (compact)
        update(std::true_type{}, current, currentLanded, from);
      else
        update(std::false_type{}, current, currentLanded, from);
    } catch (...) {
      if (walker.joinable()) walker.join();
      throw;
    }
    if (walker.joinable()) walker.join();
    std::swap(current, next);
    std::swap(currentLanded, nextLanded);
    walk = atStop;

    while (nextCurveIndex <= curvePoints_ && curveAt(nextCurveIndex) < walk.updates) ++nextCurveIndex;
    if (nextCurveIndex <= curvePoints_ && walk.updates == curveAt(nextCurveIndex)) {
      // Sampled (curve_sample): full sweeps at 20 points took about a fifth of boxing's
      // training (issue 20); the final residual below is always the whole table's.
      const Residual r = bellmanResidual(q, g, threads, curveSample_);
      result.curve.push_back({walk.updates, clock.seconds(), r.max, r.mean});
      lastResidual = r.max;
      ++nextCurveIndex;
    }
    while (nextSnapshotIndex <= snapshots && snapshotAt(nextSnapshotIndex) < walk.updates) ++nextSnapshotIndex;
    if (nextSnapshotIndex <= snapshots && walk.updates == snapshotAt(nextSnapshotIndex)) {
      // The residual of a curve point taken here, else one measured for the snapshot alone.
      CurvePoint point = !result.curve.empty() && result.curve.back().updates == walk.updates ? result.curve.back()
                                                                                              : CurvePoint{};
      if (point.updates != walk.updates) {
        Residual r;
        clock.leavingOut([&] { r = bellmanResidual(q, g, threads, curveSample_); });
        point = {walk.updates, clock.seconds(), r.max, r.mean};
      }
      takeSnapshot(*context.observer, clock, q, point);
      while (nextSnapshotIndex <= snapshots && snapshotAt(nextSnapshotIndex) <= walk.updates) ++nextSnapshotIndex;
    }
    const bool stopping = context.stop && context.stop->load(std::memory_order_relaxed) && walk.updates < total;
    // A chunk ends where an uninterrupted run's chunk ends too, so a checkpoint saved on
    // a stop resumes to the same table as one saved on schedule.
    if (context.checkpointer && walk.updates < total &&
        (stopping || (checkpointEvery_ > 0 && walk.updates % checkpointEvery_ == 0))) {
      nlohmann::json curve = nlohmann::json::array();
      for (const CurvePoint& p : result.curve) curve.push_back({p.updates, p.seconds, p.residual, p.meanResidual});
      context.checkpointer->save({{"updates", walk.updates},
                                  {"walk", toJson(walk, maxEpisode_ > 0)},
                                  {"seconds", clock.seconds()},
                                  {"curve", curve},
                                  {"cells_seen", encodeCells(cellSeen)}},
                                 q);
    }
    if (context.observer) context.observer->progress({walk.updates, total, clock.seconds(), lastResidual});
    if (stopping) throw TrainInterrupted(walk.updates, total, context.checkpointer != nullptr);
  }

  result.updates = walk.updates;
  result.finalResidual = result.curve.empty() || curveSample_ > 1 ? bellmanResidual(q, g, threads).max
                                                                   : result.curve.back().residual;
  result.seconds = clock.seconds();
  const auto cellsVisited = static_cast<std::size_t>(std::count(cellSeen.begin(), cellSeen.end(), 1));
  result.stats = {{"restarts", walk.restarts},
                  {"cells_visited", cellsVisited},
                  {"cell_coverage", cellSeen.empty() ? 0.0 : static_cast<double>(cellsVisited) / static_cast<double>(cellSeen.size())},
                  {"mean_episode_actions", walk.restarts > 0 ? static_cast<double>(walk.updates) / walk.restarts : 0.0},
                  {"resumed", resumed}};
  return result;
}

}  // namespace

void registerQLearning(LearnerRegistry& registry) {
  registry.add(
      {"q_learning",
       "the paper's Q-learning (sec. 4.2): random poses, targets and actions; every vertex next to the target "
       "updated with Q(e', .) interpolated; alpha falls linearly from 1",
       {ParamSpec::integer("budget", 10'000'000, 1, 1'000'000'000'000LL, "actions", "random actions to take"),
        ParamSpec::integer("seed", 1, 0, 9'007'199'254'740'991LL, "", "random seed: the same seed, the same table"),
        ParamSpec::number("alpha_final", 0.0, 0, 1, "", "learning rate at the end of the budget (1 at the start)"),
        ParamSpec::integer("curve_points", 20, 1, 100000, "points",
                           "training-curve points, each measuring the Bellman residual (see curve_sample)"),
        ParamSpec::integer("curve_sample", 8, 1, 1'000'000, "pairs",
                           "a curve point's residual is measured on one (action, vertex) pair in this many (every "
                           "action, spread over the grid), for that much less work; 1: all of them. The final "
                           "residual is always the whole table's"),
        ParamSpec::integer("checkpoint_every", 10'000'000, 0, 1'000'000'000'000LL, "actions",
                           "save a resumable checkpoint this often (0: never)"),
        ParamSpec::integer("max_episode_actions", 0, 0, 1'000'000'000'000LL, "actions",
                           "restart the walk after this many actions even if the target stays on the grid (0: only "
                           "when it leaves, the paper's rule)"),
        threadsSpec()},
       [](const Params& p) { return std::make_unique<QLearning>(p); },
       {},
       nullptr,
       "{type: q_learning, budget: 200000}"});  // the conformance suite's: seconds, not minutes
}

}  // namespace mgrl::learners
