// Learning benchmark (DESIGN.md sec. 7): the paper's problem sizes on a
// seed-sized synthetic state-action model (437 states, 27,072 actions of 5-40 frames at
// 15 fps, motion statistics measured from the boxing capture), with the paper's grids
// (approach: polar2d 5 x 13 within 2 m; hit: cylindrical3d 10 x 10 x 4 over the effective
// hitting points). Reports, as medians where repeated:
//   - Q-learning throughput (random actions per second, the paper's exact update) and the
//     time for the paper's budgets (approach 50 M actions, hit 400 M);
//   - one value-iteration sweep of the hit problem;
//   - one runtime decision of the combined controller;
//   - the Q tables' size;
//   - how training time grows with grid size and with the number of actions.
//   build/bench/mgrl_bench_learn [--approach-actions N] [--hit-actions N] [--runs N] [--quick] [--no-growth]
// --quick measures 10 M approach and 20 M hit actions and extrapolates to the paper's budgets.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <sys/resource.h>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "builtin_plugins.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/runtime/controller.hpp"
#include "synthetic_model.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double peakMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

mgrl::ConfigNode yaml(const std::string& text) { return mgrl::ConfigNode::parse(text, "bench"); }

struct Setup {
  std::unique_ptr<mgrl::Discretizer> grid;
  std::unique_ptr<mgrl::Reward> reward;
  mgrl::StaticTarget environment;
  mgrl::GridModel tabulated;
  double tabulateSeconds = 0;
};

std::unique_ptr<Setup> setup(const mgrl::StateActionModel& m, const std::string& grid, const std::string& reward) {
  auto s = std::make_unique<Setup>();
  s->grid = mgrl::builtinPlugins().discretizers.create(yaml(grid), m);
  s->reward = mgrl::builtinPlugins().rewards.create(yaml(reward));
  const auto start = Clock::now();
  s->tabulated = mgrl::GridModel::build({m, *s->grid, *s->reward, s->environment}, mgrl::defaultThreadCount());
  s->tabulateSeconds = since(start);
  return s;
}

mgrl::TrainResult qLearning(const mgrl::StateActionModel& m, const Setup& s, std::uint64_t actions,
                            const mgrl::GridModel* model = nullptr) {
  const auto learner = mgrl::builtinPlugins().learners.create(
      yaml("{type: q_learning, curve_points: 1, checkpoint_every: 0, budget: " + std::to_string(actions) + "}"));
  return learner->train({{m, *s.grid, *s.reward, s.environment}, model ? *model : s.tabulated, nullptr, nullptr,
                         mgrl::defaultThreadCount()});
}

double sweepSeconds(const mgrl::StateActionModel& m, const Setup& s, int runs, const mgrl::GridModel* model = nullptr) {
  const mgrl::GridModel& g = model ? *model : s.tabulated;
  mgrl::QTable a(m, g.vertexCount), b = a;
  std::vector<float> stage;
  mgrl::sweep(a, b, g, mgrl::defaultThreadCount(), stage);  // values that are not all 0
  std::vector<double> samples;
  for (int r = 0; r < runs; ++r) {
    const auto start = Clock::now();
    mgrl::sweep(b, a, g, mgrl::defaultThreadCount(), stage);
    samples.push_back(since(start));
    std::swap(a, b);
  }
  return mgrl::bench::median(samples);
}

const char* kApproachGrid = "{type: polar2d, radius: 2, rings: 5, sectors: 13}";
const char* kApproachReward = "{type: approach, sigma: 0.1, gamma: 0.97}";
const char* kHitReward = "{type: hit, contact_radius: 0.15, gamma: 0.97}";
std::string hitGrid(int angles, int distances, int heights) {
  return "{type: cylindrical3d, bounds: hits, angles: " + std::to_string(angles) +
         ", distances: " + std::to_string(distances) + ", heights: " + std::to_string(heights) + "}";
}

}  // namespace

int main(int argc, char** argv) {
  std::uint64_t approachActions = 50'000'000, hitActions = 400'000'000;
  bool noGrowth = false;
  const CLI::Option* approachOption = nullptr;
  const CLI::Option* hitOption = nullptr;
  // --quick keeps the 5 runs and takes 10 M approach and 20 M hit actions (unless given).
  const mgrl::bench::RunArgs args = mgrl::bench::parseRunArgs(
      argc, argv, "mgrl_bench_learn: Q-learning and value iteration on a seed-sized synthetic model", 5, 5,
      [&](CLI::App& app) {
        const auto actions = CLI::Range(std::uint64_t{1}, std::uint64_t{1'000'000'000'000});
        approachOption = app.add_option("--approach-actions", approachActions, "Q-learning actions on approach's grid")
                             ->check(actions);
        hitOption = app.add_option("--hit-actions", hitActions, "Q-learning actions on hit's grid")->check(actions);
        app.add_flag("--no-growth", noGrowth, "skip the runs on growing grids");
      });
  const int runs = args.runs;
  if (args.quick && approachOption->count() == 0) approachActions = 10'000'000;
  if (args.quick && hitOption->count() == 0) hitActions = 20'000'000;

  auto start = Clock::now();
  const mgrl::StateActionModel m = mgrl::makeSyntheticModel({});
  std::printf("seed-sized synthetic model: %zu states, %zu actions, %u action frames, %zu effective hits (%.2f s)\n",
              m.stateCount(), m.actionCount(), m.framesTotal, m.hits.size(), since(start));

  const auto approach = setup(m, kApproachGrid, kApproachReward);
  const auto hit = setup(m, hitGrid(10, 10, 4), kHitReward);
  const double tableMB = static_cast<double>((approach->grid->vertexCount() + hit->grid->vertexCount()) *
                                             m.actionCount() * sizeof(float)) / 1e6;
  std::printf("grids: approach %zu vertices, hit %zu vertices; tabulated in %.2f s and %.2f s (%.0f MB and %.0f MB)\n",
              approach->grid->vertexCount(), hit->grid->vertexCount(), approach->tabulateSeconds,
              hit->tabulateSeconds, approach->tabulated.bytes() / 1e6, hit->tabulated.bytes() / 1e6);
  std::printf("Q tables (float32): approach %.1f MB + hit %.1f MB = %.1f MB   (target <= 55 MB; paper 50 MB)\n",
              approach->grid->vertexCount() * m.actionCount() * 4 / 1e6,
              hit->grid->vertexCount() * m.actionCount() * 4 / 1e6, tableMB);

  // Q-learning, the paper's exact update, one thread (the algorithm is sequential).
  for (const auto& [name, s, actions, paper, target, budget] :
       {std::tuple{"approach", approach.get(), approachActions, "2 h", 10.0, 50e6},
        std::tuple{"hit", hit.get(), hitActions, "15 h", 120.0, 400e6}}) {
    const mgrl::TrainResult r = qLearning(m, *s, actions);
    const double rate = static_cast<double>(r.updates) / r.seconds;
    std::printf("q_learning %-8s %llu actions in %.2f s: %.2f M actions/s -> the paper's %.0f M in %.1f s "
                "(target <= %.0f s; paper %s); %.1f actions per episode\n",
                name, static_cast<unsigned long long>(r.updates), r.seconds, rate / 1e6, budget / 1e6, budget / rate,
                target, paper, r.stats["mean_episode_actions"].get<double>());
  }

  std::printf("value iteration sweep, hit problem (%zu vertex-action pairs): %.3f s median of %d (target <= 0.15 s)\n",
              hit->tabulated.vertexCount * m.actionCount(), sweepSeconds(m, *hit, runs), runs);

  // What bounds the sweep (docs/performance.md): each backup that lands on the grid reads
  // 8 rows of its end state's Q values (padded to 16 floats, the vector width), from the
  // second-level cache, since one end state's block of rows is about 100 KB.
  {
    double rowBytes = 0;
    const mgrl::GridModel& g = hit->tabulated;
    for (std::size_t a = 0; a < g.actionCount; ++a) {
      const double n = static_cast<double>(m.stateActionBegin[g.actionTo[a] + 1] - m.stateActionBegin[g.actionTo[a]]);
      const double padded = 16 * std::ceil(n / 16);
      for (std::size_t v = 0; v < g.vertexCount; ++v)
        if (g.transition[a * g.vertexCount + v].cell >= 0) rowBytes += 8 * padded * sizeof(float);
    }
    std::printf("  a sweep reads %.1f GB of Q rows (8 per backup that lands on the grid) and %.0f MB of transitions\n",
                rowBytes / 1e9, static_cast<double>(g.transition.size() * sizeof(mgrl::GridTransition)) / 1e6);
  }

  // The compact model (train --model compact): rewards only, landings found per
  // backup. The same tables (tests/learning_test.cpp); here its memory and speed.
  {
    const auto compactStart = Clock::now();
    const mgrl::GridModel compact =
        mgrl::GridModel::buildCompact({m, *hit->grid, *hit->reward, hit->environment}, mgrl::defaultThreadCount());
    const double built = since(compactStart);
    const double qMB = hit->grid->vertexCount() * m.actionCount() * 4 / 1e6;
    std::printf("compact model, hit problem: %.0f MB (%.2fx its Q table; tabulated %.0f MB, %.2fx) built in %.2f s\n",
                compact.bytes() / 1e6, compact.bytes() / 1e6 / qMB, hit->tabulated.bytes() / 1e6,
                hit->tabulated.bytes() / 1e6 / qMB, built);
    const std::uint64_t actions = std::min<std::uint64_t>(hitActions, 20'000'000);
    const mgrl::TrainResult r = qLearning(m, *hit, actions, &compact);
    std::printf("  q_learning hit %llu actions in %.2f s: %.2f M actions/s; value iteration sweep %.3f s median of %d\n",
                static_cast<unsigned long long>(r.updates), r.seconds, static_cast<double>(r.updates) / r.seconds / 1e6,
                sweepSeconds(m, *hit, runs, &compact), runs);
  }

  // A runtime decision: both behaviours, random states and targets in the approach region.
  {
    mgrl::QTable qa(m, approach->grid->vertexCount()), qh(m, hit->grid->vertexCount()), scratch = qa;
    mgrl::sweep(mgrl::QTable(qa), qa, approach->tabulated, 2);
    mgrl::sweep(mgrl::QTable(qh), qh, hit->tabulated, 2);
    mgrl::PolicyController controller(m, {{approach->grid.get(), &qa, 1.0, mgrl::Activation::Always},
                                          {hit->grid.get(), &qh, 1.0, mgrl::Activation::TargetInside}});
    mgrl::Rng rng(3);
    std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> queries(100000);
    std::size_t inside = 0;
    for (auto& [s, e] : queries) {
      s = static_cast<std::uint32_t>(rng.below(m.stateCount()));
      e = (rng.uniform() < 0.5 ? approach : hit)->grid->sample({rng.uniform(), rng.uniform(), rng.uniform(), 0}).position;
      e.y() = m.centroid[1];
      inside += hit->grid->inside(e);
    }
    std::vector<double> samples;
    std::size_t sink = 0;
    for (int r = 0; r < runs; ++r) {
      const auto t = Clock::now();
      for (const auto& [s, e] : queries) sink += controller.choose(s, e);
      samples.push_back(since(t) / static_cast<double>(queries.size()));
    }
    std::printf("runtime decision, random state and target each time (approach + hit, %.0f %% of targets inside the "
                "hit grid, %.1f actions per state): %.3f us median (target <= 0.5 us) [%zu]\n",
                100.0 * inside / queries.size(), static_cast<double>(m.actionCount()) / m.stateCount(),
                mgrl::bench::median(samples) * 1e6, sink % 10);
    // As at run time: the avatar follows its own choices towards a target that stays put,
    // a new target every 30 decisions.
    samples.clear();
    for (int r = 0; r < runs; ++r) {
      std::uint32_t s = 0;
      Eigen::Vector3d e(0, m.centroid[1], 1);
      const auto t = Clock::now();
      for (std::size_t i = 0; i < queries.size(); ++i) {
        if (i % 30 == 0) e = queries[i].second;
        const std::size_t a = controller.choose(s, e);
        e = approach->environment.next(m, a, e).position;
        s = m.actionTo[a];
        sink += a;
      }
      samples.push_back(since(t) / static_cast<double>(queries.size()));
    }
    std::printf("runtime decision along the avatar's own path (target moved every 30 decisions): %.3f us median, "
                "environment step included [%zu]\n",
                mgrl::bench::median(samples) * 1e6, sink % 10);
  }

  // Growth with grid size (hit problem) and with the number of actions.
  if (noGrowth) {
    std::printf("peak memory %.0f MB\n", peakMegabytes());
    return 0;
  }
  std::printf("growth with the hit grid (27,072 actions): vertices, Q-learning M actions/s, sweep s\n");
  for (const auto& [a, d, h] : {std::tuple{5, 5, 2}, std::tuple{10, 10, 4}, std::tuple{20, 20, 8}}) {
    const auto s = setup(m, hitGrid(a, d, h), kHitReward);
    const mgrl::TrainResult r = qLearning(m, *s, 5'000'000);
    std::printf("  %2dx%2dx%d %6zu vertices  %6.2f M actions/s  sweep %.3f s  table %.0f MB\n", a, d, h,
                s->grid->vertexCount(), r.updates / r.seconds / 1e6, sweepSeconds(m, *s, std::min(runs, 3)),
                s->grid->vertexCount() * m.actionCount() * 4 / 1e6);
  }
  std::printf("growth with the number of actions (437 states, 10x10x4 hit grid): actions, Q-learning M actions/s, "
              "sweep s\n");
  for (const std::size_t actions : {6768u, 13536u, 27072u, 54144u}) {
    mgrl::SyntheticModelSpec spec;
    spec.actions = actions;
    const mgrl::StateActionModel model = mgrl::makeSyntheticModel(spec);
    const auto s = setup(model, hitGrid(10, 10, 4), kHitReward);
    const mgrl::TrainResult r = qLearning(model, *s, 5'000'000);
    std::printf("  %6zu actions  %6.2f M actions/s  sweep %.3f s\n", actions, r.updates / r.seconds / 1e6,
                sweepSeconds(model, *s, std::min(runs, 3)));
  }
  std::printf("peak memory %.0f MB\n", peakMegabytes());
  return 0;
}
