#pragma once
/// \file
/// adaptive_value_iteration's learner, private to this folder: value iteration on a kd_tree
/// grid that it refines where a splitting criterion ranks the leaves highest (Munos & Moore
/// 2002; adaptive_value_iteration.cpp says which of their scheme it follows). The parts,
/// one file each:
///   adaptive_value_iteration.cpp           the refinement of one start (solve, split,
///                                          warm start, repeat up to the budget), train()
///                                          over the starts, the learner's registration;
///   adaptive_value_iteration_criteria.cpp  the splitting criteria: value non-linearity,
///                                          policy disagreement, influence x deviation;
///   adaptive_value_iteration_starts.cpp    several initial trees (`starts`) and the
///                                          backup gap that picks the one to keep.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/learning/learner.hpp"

namespace mgrl::learners {

/// Each leaf's score by the splitting criteria (AdaptiveValueIteration::score()).
struct LeafScores {
  std::vector<double> value;   // mean over motion states of |backup - interpolation| at the centre
  std::vector<double> policy;  // fraction of motion states whose corners disagree on the action
  // Sum over motion states of the largest influence x standard deviation at a free corner
  // (influence_policy: only the states whose corners disagree); empty unless asked for.
  std::vector<double> influence;
};

/// A reference-free error of a solution, to rank starts: the root mean square over motion
/// states and targets of V_s by one backup at the target against V_s interpolated there
/// (the value criterion's measure, Munos & Moore's value non-linearity, taken at given
/// targets instead of cell centres), and the root mean square of V_s itself there.
struct Gap {
  double gap = 0, value = 0;
  // The gap relative to the value: +infinity for a solution that is 0 at every target.
  double relative() const { return value > 0 ? gap / value : std::numeric_limits<double>::infinity(); }
};

/// V_s at target e by one backup: the best over s's out-actions of the reward plus the
/// discounted value interpolated where the target lands (0 outside the grid).
double backedUpValue(const Problem& problem, const Discretizer& grid, const GridModel& g, const QTable& q,
                     std::size_t s, const Eigen::Vector3d& e);

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
      throw Error(
          fmt::format("adaptive_value_iteration: expected a discretizer that can be refined (type kd_tree), "
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
  // What the refinements of every start add to: the training clock, the curve (a point per
  // sweep), the backups so far, and the sweeps' scratch.
  struct Progress {
    TrainingClock clock;  // snapshots (TrainObserver::snapshot) are not training
    std::vector<CurvePoint> curve;
    std::uint64_t updates = 0;
    std::vector<float> stage;
  };

  // The refinement from `restart` (null: problem.grid, with its tabulated context.grid).
  Run refine(const TrainContext& context, std::shared_ptr<const Discretizer> restart, unsigned threads,
             Progress& progress) const;
  // Value iteration on one round's tree (value_iteration's Jacobi sweeps) from `q`, with
  // `next` as the other table; the last sweep's largest change into `change`. Returns the
  // sweeps. Throws TrainInterrupted when context.stop is raised before convergence.
  std::uint64_t solve(const TrainContext& context, const GridModel& g, QTable& q, QTable& next, double& change,
                      unsigned threads, Progress& progress) const;
  // `grid` with `splits` split, or with the longest prefix of them that fits max_vertices
  // (`splits` cut to it; `budgetSpent` when none fits). Null for no splits.
  std::shared_ptr<const Discretizer> refinedWithinBudget(const Discretizer& grid, std::vector<std::uint32_t>& splits,
                                                         bool& budgetSpent) const;

  // The splitting criteria (adaptive_value_iteration_criteria.cpp).
  LeafScores score(const Problem& problem, const Discretizer& grid, const GridModel& g, const QTable& q,
                   unsigned threads) const;
  std::vector<std::uint32_t> choose(const Discretizer& grid, const LeafScores& scores) const;
  // The vertices counted against max_vertices: all of them (table rows) or the free ones.
  std::size_t counted(const Discretizer& grid) const {
    return countFree_ ? grid.vertexCount() - grid.hanging().size() : grid.vertexCount();
  }

  // The starts (adaptive_value_iteration_starts.cpp). The initial cells of each start: the
  // grid's own, then scaled by 1 - i start_step (rounded, at least 1; shapes already listed
  // are skipped).
  std::vector<std::vector<long long>> startShapes(const Discretizer& grid) const;
  // The start to keep of `runs` (0 for one): the lowest relative backup gap, ties to the
  // earlier; each run's gap is set and reported in its entry of `tried` (triedIndex[i]).
  std::size_t keptStart(const Problem& problem, std::vector<Run>& runs, nlohmann::json& tried,
                        const std::vector<std::size_t>& triedIndex, unsigned threads) const;

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

}  // namespace mgrl::learners
