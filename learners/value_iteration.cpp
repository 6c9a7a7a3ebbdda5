// value_iteration: the q_learning backup (paper sec. 4.2) swept over every (vertex,
// action) pair until nothing changes more than a tolerance: the exact answer on the grid,
// the reference other learners are measured against (DESIGN.md sec. 4).
#include <algorithm>
#include <cmath>

#include "learners.hpp"

namespace mgrl::learners {

namespace {

class ValueIteration final : public Learner {
 public:
  explicit ValueIteration(const Params& p)
      : tolerance_(p.number("tolerance")),
        maxSweeps_(static_cast<std::uint64_t>(p.integer("max_sweeps"))),
        threads_(static_cast<unsigned>(p.integer("threads"))) {}

  std::string type() const override { return "value_iteration"; }
  bool takesCompactModel() const override { return true; }

  // Jacobi sweeps of the same backup as q_learning over every (vertex, action) pair, from
  // Q = 0, until the largest change falls below the tolerance (DESIGN.md sec. 4: the
  // ground truth on the grid). Each sweep reads only the previous table (sec. 8).
  TrainResult train(const TrainContext& context) const override {
    const GridModel& g = context.grid;
    const unsigned threads = threads_ > 0 ? threads_ : context.threads;
    TrainingClock clock;  // snapshots are not training
    const std::size_t snapshots = snapshotsWanted(context.observer);
    std::size_t taken = 0;
    double previousChange = 0;
    TrainResult result;
    QTable current(context.problem.model, g.vertexCount), next = current;
    const std::uint64_t pairs = static_cast<std::uint64_t>(g.vertexCount) * g.actionCount;
    std::uint64_t sweeps = 0;
    std::vector<float> stage;
    double change = 0;
    bool converged = false;
    while (sweeps < maxSweeps_) {
      change = sweep(current, next, g, threads, stage);
      std::swap(current, next);
      ++sweeps;
      result.curve.push_back({sweeps * pairs, clock.seconds(), change, 0});
      if (context.observer) context.observer->progress({sweeps * pairs, 0, clock.seconds(), change});
      if (snapshots > 0) {
        // The sweep count is not known ahead, but the change shrinks by a nearly constant
        // factor per sweep: the sweeps left are estimated from the last two changes, and a
        // snapshot taken at each n-th of the estimated total (and at the last sweep).
        double estimate = static_cast<double>(maxSweeps_);
        if (sweeps >= 2 && change > 0 && change < previousChange)
          estimate = std::min(estimate, static_cast<double>(sweeps) + std::max(0.0, std::log(tolerance_ / change) /
                                                                                         std::log(change / previousChange)));
        const bool last = change < tolerance_ || sweeps == maxSweeps_;
        if (last || static_cast<double>(sweeps) >= estimate * static_cast<double>(taken + 1) / static_cast<double>(snapshots)) {
          takeSnapshot(*context.observer, clock, current, result.curve.back());
          ++taken;
        }
      }
      previousChange = change;
      // Sweeps are short and need no checkpoint: a stopped run starts over.
      if (context.stop && context.stop->load(std::memory_order_relaxed) && change >= tolerance_)
        throw TrainInterrupted(sweeps * pairs, 0, false);
      if (change < tolerance_) {
        converged = true;
        break;
      }
    }
    result.table = std::move(current);
    result.updates = sweeps * pairs;
    result.finalResidual = bellmanResidual(result.table, g, threads).max;
    result.seconds = clock.seconds();
    result.stats = {{"sweeps", sweeps}, {"converged", converged}, {"last_change", change}};
    return result;
  }

 private:
  double tolerance_;
  std::uint64_t maxSweeps_;
  unsigned threads_;
};

}  // namespace

ParamSpec threadsSpec() {
  return ParamSpec::integer("threads", 0, 0, 1024, "threads", "threads for sweeps (0: every core)");
}

void registerValueIteration(LearnerRegistry& registry) {
  registry.add({"value_iteration",
                "the same backup swept over every (vertex, action) pair until the largest change is below the "
                "tolerance: the exact answer on the grid",
                {ParamSpec::number("tolerance", 1e-4, 1e-9, 1, "", "stop when no value changes more than this"),
                 ParamSpec::integer("max_sweeps", 1000, 1, 1'000'000, "sweeps", "give up after this many sweeps"),
                 threadsSpec()},
                [](const Params& p) { return std::make_unique<ValueIteration>(p); }});
}

}  // namespace mgrl::learners
