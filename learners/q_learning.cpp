// q_learning: Lee & Lee 2004, sec. 4.2, as the paper states it. From a random pose (state)
// and a random target inside the grid, take uniformly random actions. After each action a
// with the target at e, update every grid vertex v of e's cell:
//     Q(v, a) += alpha (r(v, a) + gamma^t_a max_a' Q(e'_v, a') - Q(v, a)),
// where e'_v is v moved along by the action (the environment model) and Q(e'_v, .) is
// interpolated from e'_v's cell (0 when e'_v leaves the grid). Restart when the target
// itself leaves the grid (or, with max_episode_actions, after that many actions: an
// option beyond the paper for captures whose avatar hardly travels). alpha falls linearly
// from 1 over the budget of actions.
//
// The algorithm is QLearning::train(): the walk and the update (q_learning_walk.cpp) run
// chunk by chunk. What it records along the way, the learning curve, the snapshots and the
// checkpoints, is done by functions of their own below (EvenPoints, addCurvePoint(),
// snapshot(), loadCheckpoint(), saveCheckpoint()); the checkpoint's format is
// q_learning_checkpoint.cpp's.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <thread>

#include <fmt/format.h>

#include "learners.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "q_learning_checkpoint.hpp"
#include "q_learning_walk.hpp"

namespace mgrl::learners {

namespace {

// The most steps in a chunk of the walk: train() reports progress after every chunk.
constexpr std::uint64_t kProgressEvery = 1 << 16;

// Points spread evenly over the budget, at budget * i / n for i = 1..n (the learning
// curve's, the snapshots'): whether one falls where a chunk ended, and where the next
// chunk must end to meet the next one.
class EvenPoints {
 public:
  // `n` points over `total` updates; those at or before `done` (a resumed run's) are past.
  EvenPoints(std::uint64_t total, std::uint64_t n, std::uint64_t done) : total_(total), n_(n) {
    while (next_ <= n_ && at(next_) <= done) ++next_;
  }

  // `stop`, or the first point after `from` if it comes first. at() rounds down, so the
  // search starts just past from's share.
  std::uint64_t chunkEnd(std::uint64_t from, std::uint64_t stop) const {
    for (std::uint64_t i = std::max<std::uint64_t>(1, n_ > 0 ? from * n_ / total_ : 1); i <= n_; ++i)
      if (at(i) > from) return std::min(stop, at(i));
    return stop;
  }

  // Whether a point falls at `updates` that has not been taken; passes the ones before it.
  bool due(std::uint64_t updates) {
    while (next_ <= n_ && at(next_) < updates) ++next_;
    return next_ <= n_ && updates == at(next_);
  }
  // Takes every point up to `updates`.
  void take(std::uint64_t updates) {
    while (next_ <= n_ && at(next_) <= updates) ++next_;
  }

 private:
  std::uint64_t at(std::uint64_t i) const { return total_ * i / n_; }

  std::uint64_t total_, n_, next_ = 1;
};

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
  // Where the chunk from update `from` ends: at the next progress report, learning-curve
  // point, snapshot or checkpoint, whichever comes first, so that a chunk's end is never
  // later than a point where train() records something.
  std::uint64_t chunkEnd(std::uint64_t from, const EvenPoints& curve, const EvenPoints& snapshots) const;

  // The learning curve: a point (the Bellman residual, sampled per curve_sample) at
  // `updates`, appended to `curve`. Returns the residual.
  double addCurvePoint(std::vector<CurvePoint>& curve, const QTable& q, const GridModel& g, unsigned threads,
                       const TrainingClock& clock, std::uint64_t updates) const;
  // A snapshot for `observer` at `updates`, with the curve point taken there or else a
  // residual measured for it alone (left out of the training time, as the snapshot is).
  void snapshot(TrainObserver& observer, TrainingClock& clock, const QTable& q, const GridModel& g, unsigned threads,
                const std::vector<CurvePoint>& curve, std::uint64_t updates) const;

  // The checkpoint a resumed run continues from, with the table loaded into `q`; none if
  // there is no checkpointer or nothing to resume (a state that fails readSaved() is
  // reported and ignored by the checkpointer, and `q` left as it is).
  std::optional<Saved> loadCheckpoint(const TrainContext& context, QTable& q) const;
  void saveCheckpoint(Checkpointer& checkpointer, const Walk& walk, double seconds,
                      const std::vector<CurvePoint>& curve, const std::vector<std::uint8_t>& cellSeen,
                      const QTable& q) const;

  // What train() reports beside the table: restarts, the cells visited, the episodes' length.
  static nlohmann::json stats(const Walk& walk, const std::vector<std::uint8_t>& cellSeen, bool resumed);

  std::uint64_t budget_, seed_;
  double alphaFinal_;
  std::uint64_t curvePoints_, checkpointEvery_;
  std::size_t curveSample_;  ///< a curve point's residual is measured on one (action, vertex) pair in this many
  std::uint64_t maxEpisode_;  ///< 0: the paper's rule (restart only when the target leaves)
  unsigned threads_;
};

TrainResult QLearning::train(const TrainContext& context) const {
  const Discretizer& grid = context.problem.grid;
  const GridModel& g = context.grid;
  const unsigned threads = threads_ > 0 ? threads_ : context.threads;
  const std::uint64_t total = budget_;
  // Its updates move vertices one by one; a hanging vertex must follow its coarse face.
  if (!g.hanging.empty())
    throw Error(fmt::format("q_learning: the {} grid has {} hanging vertices, which its updates cannot keep "
                            "continuous; use value_iteration or adaptive_value_iteration",
                            grid.type(), g.hanging.size()));

  TrainResult result;
  result.table = QTable(context.problem.model, g.vertexCount);
  QTable& q = result.table;
  Walk walk;
  walk.rng = Rng(seed_);
  double secondsBefore = 0;
  // Cells the walk has been in (those of the run it resumes included), for the coverage
  // report: the paper's rule can keep a walk in a few cells for its whole budget.
  std::vector<std::uint8_t> cellSeen(grid.cellCount(), 0);
  QLearningWalk walker(context, maxEpisode_, cellSeen);
  std::optional<Saved> saved = loadCheckpoint(context, q);
  const bool resumed = saved.has_value();
  if (resumed) {
    walk = saved->walk;
    secondsBefore = saved->seconds;
    cellSeen = std::move(saved->cellSeen);
    result.curve = std::move(saved->curve);
  } else {
    walker.restart(walk);
  }

  TrainingClock clock(secondsBefore);  // snapshots are not training
  EvenPoints curve(total, curvePoints_, walk.updates);
  // Snapshots for an observer that wants them, at budget * i / n; none before a resume point.
  EvenPoints snapshots(total, snapshotsWanted(context.observer), walk.updates);
  double lastResidual = result.curve.empty() ? -1 : result.curve.back().residual;
  QLearningUpdate updater(g, q, total, alphaFinal_);

  // The walk (states, targets, restarts, random actions) does not depend on Q, so it is
  // walked a chunk at a time, recording (action, cell) per step and consuming the random
  // numbers in the same order as interleaving would; the updates then follow the record.
  // Knowing the steps ahead lets the update loop prefetch, and with two threads the next
  // chunk is walked while this one is updated. Chunks end at progress, curve and
  // checkpoint points, so the same seed gives the same table either way.
  // A compact model (GridModel::buildCompact) stores no transitions: the walk finds where
  // each step's corners land as it records the step, on its own thread when there are two,
  // and the updates read them in order instead of from a table.
  Walk ahead = walk;
  std::vector<WalkStep> current, next;
  std::vector<GridTransition> currentLanded, nextLanded;
  current.reserve(kProgressEvery);
  next.reserve(kProgressEvery);
  if (walk.updates < total) walker.walkChunk(ahead, chunkEnd(walk.updates, curve, snapshots), current, currentLanded);
  while (walk.updates < total) {
    const std::uint64_t from = walk.updates;
    const Walk atStop = ahead;  // the walk as it stands when this chunk's updates are done
    const std::uint64_t stop = atStop.updates;
    std::thread walking;
    if (stop < total) {
      const std::uint64_t nextStop = chunkEnd(stop, curve, snapshots);
      if (threads > 1)
        walking = std::thread([&, nextStop] { walker.walkChunk(ahead, nextStop, next, nextLanded); });
      else
        walker.walkChunk(ahead, nextStop, next, nextLanded);
    }
    try {
      updater.update(current, currentLanded, from);
    } catch (...) {
      if (walking.joinable()) walking.join();
      throw;
    }
    if (walking.joinable()) walking.join();
    std::swap(current, next);
    std::swap(currentLanded, nextLanded);
    walk = atStop;

    if (curve.due(walk.updates)) {
      lastResidual = addCurvePoint(result.curve, q, g, threads, clock, walk.updates);
      curve.take(walk.updates);
    }
    if (snapshots.due(walk.updates)) {
      snapshot(*context.observer, clock, q, g, threads, result.curve, walk.updates);
      snapshots.take(walk.updates);
    }
    const bool stopping = context.stop && context.stop->load(std::memory_order_relaxed) && walk.updates < total;
    // A chunk ends where an uninterrupted run's chunk ends too, so a checkpoint saved on
    // a stop resumes to the same table as one saved on schedule.
    if (context.checkpointer && walk.updates < total &&
        (stopping || (checkpointEvery_ > 0 && walk.updates % checkpointEvery_ == 0)))
      saveCheckpoint(*context.checkpointer, walk, clock.seconds(), result.curve, cellSeen, q);
    if (context.observer) context.observer->progress({walk.updates, total, clock.seconds(), lastResidual});
    if (stopping) throw TrainInterrupted(walk.updates, total, context.checkpointer != nullptr);
  }

  result.updates = walk.updates;
  result.finalResidual = result.curve.empty() || curveSample_ > 1 ? bellmanResidual(q, g, threads).max
                                                                   : result.curve.back().residual;
  result.seconds = clock.seconds();
  result.stats = stats(walk, cellSeen, resumed);
  return result;
}

std::uint64_t QLearning::chunkEnd(std::uint64_t from, const EvenPoints& curve, const EvenPoints& snapshots) const {
  std::uint64_t stop = std::min(budget_, from + kProgressEvery);
  stop = curve.chunkEnd(from, stop);
  // The same for snapshots: where chunks end does not change the table.
  stop = snapshots.chunkEnd(from, stop);
  if (checkpointEvery_ > 0) stop = std::min(stop, (from / checkpointEvery_ + 1) * checkpointEvery_);
  return stop;
}

double QLearning::addCurvePoint(std::vector<CurvePoint>& curve, const QTable& q, const GridModel& g, unsigned threads,
                                const TrainingClock& clock, std::uint64_t updates) const {
  // Sampled (curve_sample): full sweeps at 20 points took about a fifth of boxing's
  // training; the final residual is always the whole table's.
  const Residual r = bellmanResidual(q, g, threads, curveSample_);
  curve.push_back({updates, clock.seconds(), r.max, r.mean});
  return r.max;
}

void QLearning::snapshot(TrainObserver& observer, TrainingClock& clock, const QTable& q, const GridModel& g,
                         unsigned threads, const std::vector<CurvePoint>& curve, std::uint64_t updates) const {
  // The residual of a curve point taken here, else one measured for the snapshot alone.
  CurvePoint point = !curve.empty() && curve.back().updates == updates ? curve.back() : CurvePoint{};
  if (point.updates != updates) {
    Residual r;
    clock.leavingOut([&] { r = bellmanResidual(q, g, threads, curveSample_); });
    point = {updates, clock.seconds(), r.max, r.mean};
  }
  takeSnapshot(observer, clock, q, point);
}

std::optional<Saved> QLearning::loadCheckpoint(const TrainContext& context, QTable& q) const {
  if (!context.checkpointer) return std::nullopt;
  // The checkpointer runs this before trusting the checkpoint: a state that fails it is
  // reported and ignored there, and the table left as it is (all zeros).
  Saved saved;
  const StateCheck check = [&](const nlohmann::json& state, const ManifestReader& reader) {
    saved = readSaved(state, reader, context.problem.model.stateCount(), context.problem.grid.cellCount(), budget_,
                      curvePoints_, maxEpisode_);
  };
  if (!context.checkpointer->loadChecked(q, check)) return std::nullopt;
  return saved;
}

void QLearning::saveCheckpoint(Checkpointer& checkpointer, const Walk& walk, double seconds,
                               const std::vector<CurvePoint>& curve, const std::vector<std::uint8_t>& cellSeen,
                               const QTable& q) const {
  checkpointer.save(savedState(walk, maxEpisode_ > 0, seconds, curve, cellSeen), q);
}

nlohmann::json QLearning::stats(const Walk& walk, const std::vector<std::uint8_t>& cellSeen, bool resumed) {
  const auto cellsVisited = static_cast<std::size_t>(std::count(cellSeen.begin(), cellSeen.end(), 1));
  return {{"restarts", walk.restarts},
          {"cells_visited", cellsVisited},
          {"cell_coverage",
           cellSeen.empty() ? 0.0 : static_cast<double>(cellsVisited) / static_cast<double>(cellSeen.size())},
          {"mean_episode_actions", walk.restarts > 0 ? static_cast<double>(walk.updates) / walk.restarts : 0.0},
          {"resumed", resumed}};
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
