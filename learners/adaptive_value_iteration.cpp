// adaptive_value_iteration: variable resolution after R. Munos and A. Moore, "Variable
// resolution discretization in optimal control", Machine Learning 49 (2002). Their
// top-down scheme: start from a coarse kd-trie, solve the discrete problem on it, split the
// cells a splitting criterion ranks highest ("with some rate"), re-solve, repeat. Of their
// criteria this implements the local ones (the section "splitting methods based on local
// considerations"): value non-linearity (the backup at a cell's centre against the value
// interpolated there from its corners), policy disagreement (the corners' greedy actions
// differ) and the combination of the two; and their non-local influence x standard
// deviation criterion (influenceField() in adaptive_value_iteration_criteria.cpp). On a
// kd_tree with refinement: conforming a split also splits neighbours, so a round's vertex
// count is checked after refining (see refinedWithinBudget()). Interpolation is multilinear
// in the kd_tree's boxes, not their Kuhn triangulation, so that the runtime controller
// interpolates as it does on the fixed grids.
//
// Each solve is value_iteration's (the same framework sweep and backup), warm-started from
// the previous tree's solution interpolated onto the new vertices. Nothing is random: the
// same problem and parameters give the same tree and table.
//
// This file is the refinement loop; the criteria and the choice among several starts are
// beside it (adaptive_value_iteration.hpp lists the parts).
#include "adaptive_value_iteration.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "learners.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"

namespace mgrl::learners {

namespace {

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

}  // namespace

TrainResult AdaptiveValueIteration::train(const TrainContext& context) const {
  const Problem& problem = context.problem;
  const unsigned threads = threads_ > 0 ? threads_ : context.threads;
  Progress progress;  // its clock starts here
  checkGrid(problem.grid);
  if (counted(problem.grid) > maxVertices_)
    throw Error(fmt::format("adaptive_value_iteration: max_vertices: expected at least the initial tree's {} "
                            "{}vertices, found {}",
                            counted(problem.grid), countFree_ ? "free " : "", maxVertices_));

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
    runs.push_back(refine(context, std::move(restart), threads, progress));
    const Run& run = runs.back();
    triedIndex.push_back(tried.size());
    tried.push_back({{"initial_cells", shapes[i]},
                     {"vertices", run.grid->vertexCount()},
                     {"rounds", run.rounds.size()},
                     {"stopped_by", run.stopped}});
  }
  const std::size_t chosen = keptStart(problem, runs, tried, triedIndex, threads);
  if (context.observer && runs.size() > 1)
    context.observer->note(fmt::format("kept the start from {} initial cells (relative backup gap {:.4g}, of {} "
                                       "starts)",
                                       fmt::join(runs[chosen].grid->initialCells(), "x"), runs[chosen].gap.relative(),
                                       runs.size()));
  Run best = std::move(runs[chosen]);
  const nlohmann::json chosenCells = tried[triedIndex[chosen]].at("initial_cells");
  TrainResult result;
  result.curve = std::move(progress.curve);
  result.finalResidual = best.residual;
  result.table = std::move(best.q);
  result.grid = best.owned;
  result.updates = progress.updates;
  result.seconds = progress.clock.seconds();
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

AdaptiveValueIteration::Run AdaptiveValueIteration::refine(const TrainContext& context,
                                                           std::shared_ptr<const Discretizer> restart, unsigned threads,
                                                           Progress& progress) const {
  const Problem& problem = context.problem;
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
    const std::uint64_t sweeps = solve(context, g, q, next, run.change, threads, progress);
    run.sweeps += sweeps;
    if (snapshotsWanted(context.observer) > 0)  // one per round: the values converged on this tree
      takeSnapshot(*context.observer, progress.clock, q, progress.curve.back(),
                   run.grid == &problem.grid ? nullptr : run.grid);
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
    bool budgetSpent = false;
    std::shared_ptr<const Discretizer> refined = refinedWithinBudget(*run.grid, splits, budgetSpent);
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
}

std::uint64_t AdaptiveValueIteration::solve(const TrainContext& context, const GridModel& g, QTable& q, QTable& next,
                                            double& change, unsigned threads, Progress& progress) const {
  next = q;
  const std::uint64_t pairs = static_cast<std::uint64_t>(g.vertexCount) * g.actionCount;
  std::uint64_t sweeps = 0;
  while (sweeps < maxSweeps_) {
    change = sweep(q, next, g, threads, progress.stage);
    std::swap(q, next);
    ++sweeps;
    progress.updates += pairs;
    progress.curve.push_back({progress.updates, progress.clock.seconds(), change, 0});
    if (context.observer) context.observer->progress({progress.updates, 0, progress.clock.seconds(), change});
    if (context.stop && context.stop->load(std::memory_order_relaxed) && change >= tolerance_)
      throw TrainInterrupted(progress.updates, 0, false);
    if (change < tolerance_) break;
  }
  return sweeps;
}

// A conforming kd_tree splits neighbours too, so a split may add more vertices than
// choose() assumed: keep the longest prefix of the ranking that fits the budget.
std::shared_ptr<const Discretizer> AdaptiveValueIteration::refinedWithinBudget(const Discretizer& grid,
                                                                               std::vector<std::uint32_t>& splits,
                                                                               bool& budgetSpent) const {
  std::shared_ptr<const Discretizer> refined;
  if (!splits.empty()) refined = grid.refined(splits);
  if (refined && counted(*refined) > maxVertices_) {
    std::size_t fits = 0, over = splits.size();
    std::shared_ptr<const Discretizer> best;
    while (over - fits > 1) {
      const std::size_t mid = (fits + over) / 2;
      std::shared_ptr<const Discretizer> trial = grid.refined({splits.begin(), splits.begin() + mid});
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
  return refined;
}

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
