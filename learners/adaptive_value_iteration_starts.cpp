// adaptive_value_iteration's starts (adaptive_value_iteration.hpp): with `starts` above 1
// the learner refines from the scenario's initial cells and from them scaled down, and
// keeps the tree whose backup gap relative to its value is lowest. Nothing here looks at a
// reference solution.
#include <algorithm>
#include <array>
#include <cmath>

#include "adaptive_value_iteration.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/random.hpp"

namespace mgrl::learners {

namespace {

// Targets at which backupGap() compares starts: this many uniform in the grid's
// coordinates (a fixed seed), and at most kGapVertexPoints of the starts' final vertices.
constexpr std::size_t kGapPoints = 200, kGapVertexPoints = 400;
constexpr std::uint64_t kGapSeed = 7;

// The Gap of a solution at `points`. Deterministic whatever the thread count.
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

}  // namespace

// The initial cells of each start: the grid's own, then scaled by 1 - i start_step
// (rounded, at least 1; shapes already listed are skipped).
std::vector<std::vector<long long>> AdaptiveValueIteration::startShapes(const Discretizer& grid) const {
  std::vector<std::vector<long long>> out{grid.initialCells()};
  for (int i = 1; out.size() < starts_ && 1 - i * startStep_ > 0; ++i) {
    std::vector<long long> cells;
    for (long long n : out[0])
      cells.push_back(std::max(1LL, std::llround((1 - i * startStep_) * static_cast<double>(n))));
    if (std::find(out.begin(), out.end(), cells) == out.end()) out.push_back(std::move(cells));
  }
  return out;
}

std::size_t AdaptiveValueIteration::keptStart(const Problem& problem, std::vector<Run>& runs, nlohmann::json& tried,
                                              const std::vector<std::size_t>& triedIndex, unsigned threads) const {
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
      entry["relative_gap"] =
          std::isfinite(runs[i].gap.relative()) ? nlohmann::json(runs[i].gap.relative()) : nlohmann::json();
      if (runs[i].gap.relative() < runs[chosen].gap.relative()) chosen = i;
    }
  }
  return chosen;
}

}  // namespace mgrl::learners
