// Adaptive resolution benchmark on the real boxing capture's hit behaviour.
//   - Value error: value iteration on a fine uniform cylindrical3d grid is the reference;
//     uniform grids and adaptive_value_iteration kd_trees at several vertex budgets are
//     compared with it at random targets inside the hitting volume (uniform in grid
//     coordinates) at every motion state: RMSE of V_s(e) = max_a Q(e, a), greedy agreement
//     (the same action as the reference's greedy one), and the mean regret (the
//     reference's best value minus its value of the tested grid's greedy action).
//   - Decision cost of the combined policy with a kd_tree hit table against the uniform
//     one's (the runtime target: <= 0.5 us).
//
// Usage: mgrl_bench_adaptive [--quick] [--runs N] [--reference A,D,H] [--points N] [--budget A,D,H]...
//                            [--variant NAME;GRID;LEARNER]... [--start SHARE] [--pow2-start] [--no-error]
//                            [--no-decision]
// --quick uses a 30 x 24 x 9 reference and fewer budgets. --budget replaces the budgets (the
// uniform grid's vertex counts); --variant replaces the adaptive configurations (extra
// kd_tree keys; extra adaptive_value_iteration keys, YAML flow style). Unless its variant
// sets *_cells, a tree starts from the uniform grid's cells scaled down until its vertices
// are at most SHARE (0.75) of the budget (a forest of root boxes, kd_tree's any-count
// cells); --pow2-start makes it the largest power-of-two cells within SHARE instead, the
// start before kd_tree had roots.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include <fmt/format.h>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "boxing_setup.hpp"
#include "builtin_plugins.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/scenario/behaviors.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

mgrl::ConfigNode yaml(const std::string& text) { return mgrl::ConfigNode::parse(text, "bench"); }

// A hit table and the grid its vertices belong to.
struct Solution {
  std::string name;
  std::shared_ptr<const mgrl::Discretizer> grid;
  mgrl::QTable table;
  double seconds = 0;
  std::size_t hanging = 0;
};

Solution solve(const std::string& name, const mgrl::StateActionModel& model, const mgrl::Reward& reward,
               const std::string& gridYaml, const std::string& learnerYaml, unsigned threads) {
  const mgrl::StaticTarget environment;
  std::shared_ptr<const mgrl::Discretizer> grid = mgrl::builtinPlugins().discretizers.create(yaml(gridYaml), model);
  const auto start = Clock::now();
  const mgrl::Problem problem{model, *grid, reward, environment};
  const mgrl::GridModel tabulated = mgrl::GridModel::build(problem, threads);
  const auto learner = mgrl::builtinPlugins().learners.create(yaml(learnerYaml));
  mgrl::TrainResult result = learner->train({problem, tabulated, nullptr, nullptr, threads});
  Solution out;
  out.name = name;
  out.seconds = since(start);
  out.grid = result.grid ? result.grid : grid;
  out.table = std::move(result.table);
  out.hanging = out.grid->hanging().size();
  return out;
}

// Q of state s's actions at e, interpolated on `x` (false outside its grid).
bool interpolate(const Solution& x, std::uint32_t s, const Eigen::Vector3d& e, std::vector<float>& sum) {
  mgrl::GridCell cell;
  if (!x.grid->locate(e, cell)) return false;
  std::fill(sum.begin(), sum.end(), 0.0f);
  mgrl::addInterpolated(sum.data(), x.table, s, x.grid->stencil(cell), 1.0f);
  return true;
}

struct Error {
  double rmse = 0, agreement = 0, regret = 0;
};

Error compare(const Solution& x, const Solution& reference, const mgrl::StateActionModel& model,
              const std::vector<Eigen::Vector3d>& points) {
  std::size_t widest = 0;
  for (std::size_t s = 0; s < model.stateCount(); ++s) widest = std::max(widest, x.table.actionsOf(s));
  std::vector<float> a(widest + mgrl::QTable::kPadding), b(widest + mgrl::QTable::kPadding);
  double squares = 0, agree = 0, regret = 0, count = 0;
  for (std::uint32_t s = 0; s < model.stateCount(); ++s) {
    const std::size_t n = x.table.actionsOf(s);
    if (n == 0) continue;
    for (const Eigen::Vector3d& e : points) {
      if (!interpolate(x, s, e, a) || !interpolate(reference, s, e, b)) continue;
      const auto best = static_cast<std::size_t>(std::max_element(a.begin(), a.begin() + n) - a.begin());
      const auto truth = static_cast<std::size_t>(std::max_element(b.begin(), b.begin() + n) - b.begin());
      const double gap = static_cast<double>(a[best]) - b[truth];
      squares += gap * gap;
      agree += best == truth ? 1 : 0;
      regret += static_cast<double>(b[truth]) - b[best];
      count += 1;
    }
  }
  return {std::sqrt(squares / count), agree / count, regret / count};
}

}  // namespace

// A budget: the uniform grid's vertex counts (angle, distance, height); the adaptive
// trees get its vertex count as max_vertices.
struct Budget {
  std::array<int, 3> uniform;
};
// An adaptive configuration: extra kd_tree and adaptive_value_iteration YAML keys.
struct Variant {
  std::string name, grid, learner;
};

// The uniform grid's cells (vertices - 1 per axis) scaled by the largest s in (0, 1] that
// brings the tree's vertices within `share` of the budget.
std::string scaledStartCells(const std::array<int, 3>& uniform, double share) {
  const double budget = static_cast<double>(uniform[0]) * uniform[1] * uniform[2];
  std::array<long, 3> cells{1, 1, 1};
  for (int step = 100; step > 0; --step) {
    for (int i = 0; i < 3; ++i)
      cells[i] = std::max(1L, std::lround(step / 100.0 * std::max(1, uniform[i] - 1)));
    if (static_cast<double>((cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1)) <= share * budget) break;
  }
  return fmt::format(", angle_cells: {}, distance_cells: {}, height_cells: {}", cells[0], cells[1], cells[2]);
}

std::string startCells(std::size_t budget, double share) {
  std::array<std::size_t, 3> best{1, 1, 1};
  std::size_t bestVertices = 0;
  for (std::size_t d = 1; d <= 64; d *= 2)
    for (std::size_t a : {d, 2 * d})
      for (std::size_t h : {std::max<std::size_t>(1, d / 2), d}) {
        const std::size_t vertices = (a + 1) * (d + 1) * (h + 1);
        if (static_cast<double>(vertices) <= share * static_cast<double>(budget) && vertices > bestVertices) {
          best = {a, d, h};
          bestVertices = vertices;
        }
      }
  return fmt::format(", angle_cells: {}, distance_cells: {}, height_cells: {}", best[0], best[1], best[2]);
}

int main(int argc, char** argv) {
  std::vector<Budget> budgets;
  std::vector<Variant> variants;
  double startShare = 0.75;
  bool pow2Start = false, noError = false, noDecision = false;
  std::array<int, 3> reference{40, 32, 12};
  std::size_t pointCount = 3000;
  const CLI::Option* referenceOption = nullptr;
  const CLI::Option* pointsOption = nullptr;
  // A,D,H: three vertex counts of a uniform grid (angle, distance, height).
  const auto counts = [](const char* option, const std::string& text) {
    std::array<int, 3> n{};
    char end = 0;
    if (std::sscanf(text.c_str(), "%d,%d,%d%c", &n[0], &n[1], &n[2], &end) != 3 || n[0] < 2 || n[1] < 2 || n[2] < 2)
      throw CLI::ValidationError(
          fmt::format("{}: expected A,D,H (three counts of at least 2), found '{}'", option, text));
    return n;
  };
  const mgrl::bench::RunArgs args = mgrl::bench::parseRunArgs(
      argc, argv, "mgrl_bench_adaptive: adaptive value iteration against uniform grids of the same budget", 5, 3,
      [&](CLI::App& app) {
        referenceOption = app.add_option_function<std::string>(
            "--reference", [&](const std::string& text) { reference = counts("--reference", text); },
            "the uniform reference grid A,D,H (default 40,32,12; --quick 30,24,9)");
        pointsOption =
            app.add_option("--points", pointCount, "random targets of the error (default 3000; --quick 1000)")
                ->check(CLI::Range(std::size_t{1}, std::size_t{10'000'000}));
        app.add_option_function<std::vector<std::string>>(
               "--budget",
               [&](const std::vector<std::string>& texts) {
                 for (const std::string& text : texts) budgets.push_back({counts("--budget", text)});
               },
               "a uniform grid A,D,H whose vertex count is a budget (repeat for several; replaces the defaults)")
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        app.add_option_function<std::vector<std::string>>(
               "--variant",
               [&](const std::vector<std::string>& texts) {
                 // NAME;GRID KEYS;LEARNER KEYS, e.g. "conf;refinement: conforming;criterion: influence_policy"
                 for (const std::string& text : texts) {
                   const std::size_t a = text.find(';'), b = a == std::string::npos ? a : text.find(';', a + 1);
                   if (b == std::string::npos)
                     throw CLI::ValidationError(fmt::format("--variant: expected NAME;GRID;LEARNER, found '{}'", text));
                   variants.push_back({text.substr(0, a), text.substr(a + 1, b - a - 1), text.substr(b + 1)});
                 }
               },
               "an adaptive configuration NAME;GRID KEYS;LEARNER KEYS (repeat; replaces the defaults)")
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        app.add_option("--start", startShare, "a tree's start: at most this share of the budget's vertices")
            ->check(CLI::Range(0.01, 1.0));
        app.add_flag("--pow2-start", pow2Start, "start from the largest power-of-two cells within the share");
        app.add_flag("--no-error", noError, "skip the error against the reference");
        app.add_flag("--no-decision", noDecision, "skip the decision timings");
      });
  const int runs = args.runs;
  const bool quick = args.quick, error = !noError, decision = !noDecision;
  if (quick && referenceOption->count() == 0) reference = {30, 24, 9};
  if (quick && pointsOption->count() == 0) pointCount = 1000;
  try {
    const unsigned threads = mgrl::defaultThreadCount();
    // The adaptive trees: over the hitting volume, halving their longest side.
    const std::string kdBase = "type: kd_tree, bounds: hits, split_axes: longest";
    if (error) {
      // The boxing model (graph from the cache of a value-iteration training).
      const mgrl::bench::TrainedBoxing train = mgrl::bench::trainBoxing("adaptive");
      const std::unique_ptr<const mgrl::Session> session = mgrl::openSession(train.options, {.motion = false});
      fs::remove_all(train.options.cacheDir);
      const mgrl::StateActionModel& model = session->model();
      // The scenario's hit reward.
      const std::vector<mgrl::Behavior>& behaviors = session->behaviors;
      const auto hit = std::find_if(behaviors.begin(), behaviors.end(), [](const mgrl::Behavior& b) { return b.name == "hit"; });
      if (hit == behaviors.end()) throw mgrl::Error("boxing.yaml: expected a behaviour 'hit', found none");
      const mgrl::Reward* reward = hit->reward.get();
      const std::string vi = "{type: value_iteration}";
      auto uniform = [](int a, int d, int h) {
        return fmt::format("{{type: cylindrical3d, angles: {}, distances: {}, heights: {}, bounds: hits}}", a, d, h);
      };
      const auto start = Clock::now();
      const Solution truth = solve("reference", model, *reward, uniform(reference[0], reference[1], reference[2]),
                                   vi, threads);
      std::printf("boxing hit: %zu states, %zu actions; reference: value iteration on a %d x %d x %d uniform grid "
                  "(%zu vertices, %.1f s); %zu random targets x every state\n",
                  model.stateCount(), model.actionCount(), reference[0], reference[1], reference[2],
                  truth.grid->vertexCount(), since(start), pointCount);
      mgrl::Rng rng(7);
      std::vector<Eigen::Vector3d> points;
      for (std::size_t i = 0; i < pointCount; ++i)
        points.push_back(truth.grid->sample({rng.uniform(), rng.uniform(), rng.uniform(), 0}).position);

      if (budgets.empty())
        budgets = quick ? std::vector<Budget>{{{8, 6, 5}}, {{10, 8, 6}}, {{20, 16, 6}}}
                        : std::vector<Budget>{{{6, 5, 4}}, {{8, 6, 5}}, {{10, 8, 6}}, {{14, 12, 6}}, {{20, 16, 6}}};
      if (variants.empty())
        variants = {{"conforming value", "refinement: conforming", "criterion: value"},
                    {"conforming value starts 3", "refinement: conforming", "criterion: value, starts: 3"},
                    {"local both", "", "criterion: both"},
                    {"local influence_policy", "", "criterion: influence_policy"},
                    {"conforming both", "refinement: conforming", "criterion: both"},
                    {"conforming influence_policy", "refinement: conforming", "criterion: influence_policy"}};
      std::printf("\n%-44s %8s %8s %8s %10s %9s %9s %10s %8s\n", "grid", "vertices", "free", "tied", "table B", "RMSE",
                  "agree", "regret", "train s");
      auto row = [&](const Solution& x) {
        const Error e = compare(x, truth, model, points);
        std::printf("%-44s %8zu %8zu %8zu %10zu %9.5f %8.2f%% %10.6f %8.2f\n", x.name.c_str(), x.grid->vertexCount(),
                    x.grid->vertexCount() - x.hanging, x.hanging, x.table.bytes(), e.rmse, 100 * e.agreement,
                    e.regret, x.seconds);
        std::fflush(stdout);
      };
      for (const Budget& b : budgets) {
        const auto [a, d, h] = b.uniform;
        const std::size_t vertices =
            static_cast<std::size_t>(a) * static_cast<std::size_t>(d) * static_cast<std::size_t>(h);
        row(solve(fmt::format("uniform {}x{}x{}", a, d, h), model, *reward, uniform(a, d, h), vi, threads));
        for (const Variant& v : variants) {
          // Unless the variant says, the tree starts as the uniform grid's cells scaled down to
          // `startShare` of the budget; with --pow2-start as the largest power-of-two cells of
          // the uniform grids' proportions (angle d or 2d, height d/2 or d cells for d distance
          // cells) within it.
          const std::string cells = v.grid.find("_cells") != std::string::npos ? ""
                                    : pow2Start ? startCells(vertices, startShare)
                                                : scaledStartCells(b.uniform, startShare);
          std::string grid = "{" + kdBase;
          grid += cells;
          if (!v.grid.empty()) grid += ", " + v.grid;
          grid += "}";
          // The start cells in the name ("8x6x4"), so that a row can be trained again by hand.
          std::string shape;
          for (const char* key : {"angle_cells: ", "distance_cells: ", "height_cells: "})
            if (const std::size_t at = grid.find(key); at != std::string::npos)
              shape += fmt::format("{}{}", shape.empty() ? "" : "x", std::atoi(grid.c_str() + at + std::strlen(key)));
          row(solve(fmt::format("adaptive {} {} {}", vertices, v.name, shape), model, *reward, grid,
                    fmt::format("{{type: adaptive_value_iteration, max_vertices: {}{}}}", vertices,
                                v.learner.empty() ? "" : ", " + v.learner),
                    threads));
        }
      }
    }

    if (decision) {
      // The combined controller (approach on its polar grid, hit on a refined kd_tree), the
      // same queries as mgrl_bench_runtime's.
      namespace fs = std::filesystem;
      const fs::path scratch = fs::temp_directory_path() / fmt::format("mgrl-bench-adaptive-{}", ::getpid());
      auto controllerFor = [&](const std::vector<std::string>& sets, auto&& use) {
        const mgrl::bench::TrainedBoxing train = mgrl::bench::trainBoxing("adaptive", sets);
        mgrl::SessionNeeds needs;
        needs.policy = mgrl::PolicyNeed::Required;
        needs.policyDir = train.policy;
        needs.motion = false;
        const std::unique_ptr<const mgrl::Session> session = mgrl::openSession(train.options, needs);
        mgrl::PolicyController greedy(session->model(), session->policy);
        use(session->model(), greedy);
      };
      auto time = [&](const mgrl::StateActionModel& model, mgrl::Controller& c) {
        const std::vector<mgrl::bench::DecisionQuery> queries = mgrl::bench::decisionQueries(model);
        return mgrl::bench::decisionSeconds(c, queries, queries.size(), runs);
      };
      std::printf("\ndecision cost of the combined policy (greedy), 2000 random (state, target) queries, median of "
                  "%d runs (target <= 0.5 us)\n",
                  runs);
      const std::string approach = "behaviors.approach.learner.type=value_iteration";
      controllerFor({approach, "behaviors.hit.learner.type=value_iteration"},
                    [&](const mgrl::StateActionModel& m, mgrl::Controller& c) {
                      std::printf("  %-44s %8.3f us\n", "hit uniform 20x16x6 (1,920 vertices)", 1e6 * time(m, c));
                    });
      // The trees of the error table's default start (the uniform grid's cells scaled to 75 %
      // of the budget: forests of root boxes) and criterion.
      struct Tree {
        int budget, a, d, h;
      };
      for (const Tree& t : {Tree{480, 8, 6, 4}, Tree{1920, 17, 13, 4}})
        controllerFor({approach, "behaviors.hit.discretizer.type=kd_tree", "behaviors.hit.discretizer.bounds=hits",
                       "behaviors.hit.discretizer.split_axes=longest", "behaviors.hit.discretizer.refinement=conforming",
                       fmt::format("behaviors.hit.discretizer.angle_cells={}", t.a),
                       fmt::format("behaviors.hit.discretizer.distance_cells={}", t.d),
                       fmt::format("behaviors.hit.discretizer.height_cells={}", t.h),
                       "behaviors.hit.learner.type=adaptive_value_iteration",
                       fmt::format("behaviors.hit.learner.max_vertices={}", t.budget),
                       "behaviors.hit.learner.criterion=value"},
                      [&](const mgrl::StateActionModel& m, mgrl::Controller& c) {
                        std::printf("  %-44s %8.3f us\n",
                                    fmt::format("hit kd_tree {}x{}x{} start, {} vertices", t.a, t.d, t.h, t.budget)
                                        .c_str(),
                                    1e6 * time(m, c));
                      });
      fs::remove_all(scratch);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mgrl_bench_adaptive: %s\n", e.what());
    return 1;
  }
  return 0;
}
