// The learning framework on problems whose answers are known by hand: interpolation,
// rewards, the static-target environment, value iteration and Q-learning (paper sec. 4).
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <thread>
#include <utility>

#include <fmt/format.h>

#include "app/plugins.hpp"
#include "environments/environments.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/checkpoint_store.hpp"
#include "mgrl/learning/policy_evaluation.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_learning_steps.hpp"
#include "mgrl/learning/success.hpp"
#include "mgrl/motion/roles.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/session/compare_tables.hpp"
#include "mgrl/session/trials.hpp"
#include "synthetic_model.hpp"
#include "test_support.hpp"

namespace mgrl::learning_test {
namespace {

// An action for hand-made models: frames, a straight root path to (dx, dz, dyaw), hits.
struct HandAction {
  std::uint32_t from, to, frames;
  double dx, dz, dyaw;
  std::vector<ActionHit> hits;  // action index filled in
};

// A model with only what learners, rewards and controllers read. The centroid (0, 1, 0.5)
// rides along with the avatar, as in the graph builder.
StateActionModel handModel(std::size_t states, std::vector<HandAction> actions, double frameTime = 1.0 / 30) {
  std::stable_sort(actions.begin(), actions.end(), [](const HandAction& a, const HandAction& b) { return a.from < b.from; });
  StateActionModel m;
  m.frameTime = frameTime;
  m.stateFrame.resize(states);
  m.stateActionBegin.assign(states + 1, 0);
  m.actionFrameBegin.push_back(0);
  m.actionHitBegin.push_back(0);
  m.centroid[0] = 0;
  m.centroid[1] = 1;
  m.centroid[2] = 0.5;
  for (std::size_t a = 0; a < actions.size(); ++a) {
    const HandAction& h = actions[a];
    m.actionFrom.push_back(h.from);
    m.actionTo.push_back(h.to);
    ++m.stateActionBegin[h.from + 1];
    m.actionDisplacement.insert(m.actionDisplacement.end(), {h.dx, h.dz, h.dyaw});
    for (std::uint32_t t = 1; t <= h.frames; ++t) {
      const double f = static_cast<double>(t) / h.frames;
      const GroundMotion root{f * h.dx, f * h.dz, f * h.dyaw};
      m.actionFrames.push_back(0);
      m.frameRoot.insert(m.frameRoot.end(), {root.dx, root.dz, root.dyaw});
      const Eigen::Vector3d c = transformPoint(root, {m.centroid[0], m.centroid[1], m.centroid[2]});
      m.frameCentroid.insert(m.frameCentroid.end(), {float(c.x()), float(c.y()), float(c.z())});
      m.frameEntersTransition.push_back(0);
    }
    m.actionFrameBegin.push_back(static_cast<std::uint32_t>(m.actionFrames.size()));
    for (ActionHit hit : h.hits) {
      hit.action = static_cast<std::uint32_t>(a);
      m.hits.push_back(hit);
    }
    m.actionHitBegin.push_back(static_cast<std::uint32_t>(m.hits.size()));
  }
  for (std::size_t s = 0; s < states; ++s) m.stateActionBegin[s + 1] += m.stateActionBegin[s];
  m.framesTotal = static_cast<std::uint32_t>(m.actionFrames.size());
  return m;
}

// A vertex's grid coordinates from the axes (its position loses the angle at distance 0).
std::array<double, 3> vertexCoordinates(const Discretizer& grid, std::size_t v) {
  std::array<double, 3> c{0, 0, 0};
  for (int i = 0; i < grid.dimension(); ++i) {
    const std::vector<double>& axis = grid.axes()[i].vertices;
    c[i] = axis[v % axis.size()];
    v /= axis.size();
  }
  return c;
}

ConfigNode yaml(const std::string& text) { return ConfigNode::parse(text, "test.yaml"); }

std::unique_ptr<Discretizer> makeGrid(const std::string& text, const StateActionModel& m) {
  return app::plugins().discretizers.create(yaml(text), m);
}

// The corridor: one state, three 5-frame self-loops. forward walks 0.5 m, back walks
// -0.5 m, punch stays and lands an effective hit 0.5 m ahead at height 1 on frame 3. The
// grid's centre line (angle 0, height 1) has vertices every 0.5 m from 0.5 to 3 m, and
// both walks move a target on it exactly onto the next vertex: interpolation is exact
// there and the values are known in closed form.
StateActionModel corridor() {
  const ActionHit punch{0, 3, 1, 0.0f, 1.0f, 0.5f, 1.0f};
  return handModel(1, {{0, 0, 5, 0, 0.5, 0, {}}, {0, 0, 5, 0, -0.5, 0, {}}, {0, 0, 5, 0, 0, 0, {punch}}});
}

constexpr const char* kCorridorGrid =
    "{type: cylindrical3d, bounds: given, angles: 3, distances: 6, heights: 3, angle_min: -10, angle_max: 10, "
    "distance_min: 0.5, distance_max: 3.0, height_min: 0.5, height_max: 1.5}";

struct Built {
  std::unique_ptr<Discretizer> grid;
  std::unique_ptr<Reward> reward;
  StaticTarget environment;
};

// The corridor's parts, its problem and the problem on the grid, built once per test.
struct CorridorSetup {
  // The corridor's model, or another one on the same grid and reward.
  explicit CorridorSetup(unsigned threads, StateActionModel m = corridor())
      : model(std::move(m)),
        grid(makeGrid(kCorridorGrid, model)),
        reward(app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.1}"))),
        problem{model, *grid, *reward, environment},
        tabulated(GridModel::build(problem, threads)) {}
  StateActionModel model;
  std::unique_ptr<Discretizer> grid;
  std::unique_ptr<Reward> reward;
  StaticTarget environment;
  Problem problem;
  GridModel tabulated;
  CorridorSetup(const CorridorSetup&) = delete;  // problem refers to the members
  CorridorSetup& operator=(const CorridorSetup&) = delete;
};

Built corridorParts(const StateActionModel& m) {
  return {makeGrid(kCorridorGrid, m), app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.1}")), {}};
}

// The vertex on the centre line at distance 0.5 (k + 1).
std::size_t centre(const Discretizer&, int k) { return 1 + 3 * static_cast<std::size_t>(k) + 3 * 6 * 1; }

TrainResult trainWith(const std::string& learnerYaml, const Problem& problem, const GridModel& g,
                      Checkpointer* checkpointer = nullptr) {
  const auto learner = app::plugins().learners.create(yaml(learnerYaml));
  return learner->train({problem, g, nullptr, checkpointer, 2});
}

}  // namespace

TEST_CASE("interpolation weights sum to 1 and reproduce functions linear in the grid coordinates", "[learning]") {
  const StateActionModel m = corridor();
  const auto polar = makeGrid("{type: polar2d, radius: 2, rings: 5, sectors: 13}", m);
  const auto cyl = makeGrid(kCorridorGrid, m);
  Rng rng(7);
  for (const Discretizer* grid : {polar.get(), cyl.get()}) {
    // f = 0.3 + 0.7 angle - 1.1 distance + 0.4 height, evaluated at the vertices and interpolated.
    auto f = [&](const std::array<double, 3>& c) { return 0.3 + 0.7 * c[0] - 1.1 * c[1] + 0.4 * c[2]; };
    for (int trial = 0; trial < 500; ++trial) {
      std::array<double, 4> u{rng.uniform(), rng.uniform(), rng.uniform(), 0};
      if (grid == polar.get()) u[0] = 0.02 + 0.9 * u[0];  // stay off the seam, where angle jumps by 2 pi
      const Eigen::Vector3d e = grid->sample(u).position;
      GridCell cell;
      REQUIRE(grid->locate(e, cell));
      const Stencil s = grid->stencil(cell);
      double sum = 0, value = 0;
      for (int k = 0; k < s.size; ++k) {
        REQUIRE(s.weight[k] >= 0);
        sum += s.weight[k];
        value += s.weight[k] * f(vertexCoordinates(*grid, s.vertex[k]));
      }
      REQUIRE(sum == Approx(1).margin(1e-6));
      REQUIRE(value == Approx(f(grid->coordinates(e))).margin(1e-5));
    }
  }
}

TEST_CASE("polar2d wraps the angle around the full circle", "[learning]") {
  const StateActionModel m = corridor();
  const auto polar = makeGrid("{type: polar2d, radius: 2, rings: 5, sectors: 13}", m);
  REQUIRE(polar->vertexCount() == 65);
  REQUIRE(polar->cellCount() == 13 * 4);  // 13 sectors wrap: 13 angular cells
  // Straight behind, slightly to the right and to the left: the same cell, between the last
  // angle vertex and the first one (-180 deg).
  const double step = 2 * M_PI / 13;
  const double last = -M_PI + 12 * step;
  const Eigen::Vector3d behind(std::sin(last + 0.25 * step), 0, std::cos(last + 0.25 * step));
  GridCell cell;
  REQUIRE(polar->locate(behind, cell));
  const Stencil s = polar->stencil(cell);
  std::set<std::size_t> angles;
  for (int k = 0; k < s.size; ++k) angles.insert(s.vertex[k] % 13);
  REQUIRE(angles == std::set<std::size_t>{0, 12});
  REQUIRE(cell.frac[0] == Approx(0.25).margin(1e-5));
  // A point beyond the radius is outside; clamped, it sits on the outer ring.
  REQUIRE_FALSE(polar->inside({0, 0, 2.5}));
  const GridCell clamped = polar->locateClamped({0, 0, 2.5});
  REQUIRE(clamped.frac[1] == Approx(1));
}

TEST_CASE("cylindrical3d takes its bounds from the effective hitting points", "[learning]") {
  const ActionHit a{0, 1, 0, 0.3f, 1.2f, 0.6f, 1.0f}, b{0, 2, 1, -0.2f, 1.5f, 0.4f, 0.5f};
  const StateActionModel m = handModel(1, {{0, 0, 5, 0, 0, 0, {a, b}}, {0, 0, 5, 0, 0.1, 0, {}}});
  const auto grid = makeGrid("{type: cylindrical3d}", m);
  REQUIRE(grid->vertexCount() == 400);
  const auto& axes = grid->axes();
  REQUIRE(axes[0].vertices.front() == Approx(std::atan2(-0.2, 0.4)));
  REQUIRE(axes[0].vertices.back() == Approx(std::atan2(0.3, 0.6)));
  REQUIRE(axes[1].vertices.front() == Approx(std::hypot(-0.2, 0.4)));
  REQUIRE(axes[1].vertices.back() == Approx(std::hypot(0.3, 0.6)));
  REQUIRE(axes[2].vertices.front() == Approx(1.2));
  REQUIRE(axes[2].vertices.back() == Approx(1.5));
  REQUIRE_FALSE(axes[0].wraps);
  // Both hitting points are inside their own grid.
  REQUIRE(grid->inside(Eigen::Vector3f(0.3f, 1.2f, 0.6f).cast<double>()));
  REQUIRE(grid->inside(Eigen::Vector3f(-0.2f, 1.5f, 0.4f).cast<double>()));
  REQUIRE_FALSE(grid->inside({0.3, 1.6, 0.6}));
  // Without hits there is nothing to take bounds from.
  const StateActionModel none = handModel(1, {{0, 0, 5, 0, 0, 0, {}}, {0, 0, 5, 0, 0.1, 0, {}}});
  REQUIRE_THROWS_WITH(makeGrid("{type: cylindrical3d}", none),
                      Catch::Contains("test.yaml:1:1: bounds: expected at least 2 effective hitting points"));
}

TEST_CASE("rewards match hand-computed values on a tiny action", "[learning]") {
  // One 4-frame action walking 0.4 m ahead: the centroid (0, 1, 0.5) moves to z = 0.6, 0.7,
  // 0.8, 0.9; an effective hit at frame 2, 0.6 m ahead at height 1.3, weight 0.5.
  const ActionHit hit{0, 2, 1, 0.0f, 1.3f, 0.6f, 0.5f};
  const StateActionModel m = handModel(1, {{0, 0, 4, 0, 0.4, 0, {hit}}, {0, 0, 4, 0, 0, 0, {}}});
  const auto approach = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.1, gamma: 0.9}"));
  // Target 0.8 m ahead: frame 3 reaches it, 0.9^3 exp(0) beats 0.9^2 exp(-1) and 0.9^4 exp(-1).
  REQUIRE(approach->evaluate(m, 0, {0, 0, 0.8}) == Approx(0.729));
  // Target 0.2 m to the side of frame 1's centroid (0, 0.6): 0.9 exp(-2) vs 0.9^2 exp(-sqrt(0.05)/0.1).
  const double expected = std::max(0.9 * std::exp(-2.0), 0.81 * std::exp(-std::sqrt(0.05) / 0.1));
  REQUIRE(approach->evaluate(m, 0, {0.2, 0, 0.6}) == Approx(expected));
  const auto hitReward = app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.1, gamma: 0.9}"));
  REQUIRE(hitReward->evaluate(m, 0, {0, 1.3, 0.6}) == Approx(0.81 * 0.5));
  REQUIRE(hitReward->evaluate(m, 0, {0.05, 1.3, 0.65}) == Approx(0.81 * 0.5));  // 7 cm away
  REQUIRE(hitReward->evaluate(m, 0, {0, 1.3, 0.75}) == 0);                        // 15 cm away
  REQUIRE(hitReward->evaluate(m, 1, {0, 1.3, 0.6}) == 0);                         // no hit in action 1
  const auto flat = app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.1, gamma: 0.9, use_speed: false}"));
  REQUIRE(flat->evaluate(m, 0, {0, 1.3, 0.6}) == Approx(0.81));
}

TEST_CASE("static_target sees a fixed world point from the action's end", "[learning]") {
  const StateActionModel m = handModel(1, {{0, 0, 5, 0.3, 0.4, 0.7, {}}, {0, 0, 5, 0, 0, 0, {}}});
  const StaticTarget environment;
  const Eigen::Vector3d e(0.5, 1.2, 1.5);
  const Eigen::Vector3d next = environment.next(m, 0, e).position;
  // Back into the decision's frame, it is where it was.
  const Eigen::Vector3d back = transformPoint(m.displacement(0), next);
  REQUIRE((back - e).norm() < 1e-12);
  REQUIRE(next.y() == 1.2);
}

TEST_CASE("value iteration gives the corridor's closed-form values", "[learning]") {
  const CorridorSetup parts(2);
  const Problem& problem = parts.problem;
  const GridModel& g = parts.tabulated;
  const TrainResult vi = trainWith("{type: value_iteration, tolerance: 1e-7}", problem, g);
  REQUIRE(vi.stats["converged"] == true);
  const double gamma = 0.97, v0 = std::pow(gamma, 3) / (1 - std::pow(gamma, 5));
  // At 0.5 m punching forever is best; further out, walk forward then punch.
  REQUIRE(vi.table.at(2, centre(*parts.grid, 0)) == Approx(v0).epsilon(1e-5));
  REQUIRE(vi.table.at(0, centre(*parts.grid, 0)) == Approx(0).margin(1e-6));  // walks out of the grid
  for (int k = 1; k < 6; ++k) {
    const double vk = std::pow(gamma, 5 * k) * v0;
    REQUIRE(vi.table.at(0, centre(*parts.grid, k)) == Approx(vk).epsilon(1e-5));
    REQUIRE(vi.table.at(2, centre(*parts.grid, k)) == Approx(std::pow(gamma, 5) * vk).epsilon(1e-5));
  }
  REQUIRE(vi.finalResidual < 1e-6);
}

TEST_CASE("a learner's training clock leaves out what it is told to and adds a resumed run's time", "[learning]") {
  const auto sleep = [] { std::this_thread::sleep_for(std::chrono::milliseconds(150)); };
  mgrl::TrainingClock clock;
  clock.leavingOut(sleep);
  CHECK(clock.seconds() < 0.1);  // the 150 ms slept are not training
  sleep();
  const double trained = clock.seconds();
  CHECK(trained >= 0.15);
  clock.leaveOut(trained);
  CHECK(clock.seconds() < 0.1);
  const mgrl::TrainingClock resumed(100);
  CHECK(resumed.seconds() >= 100);
  CHECK(resumed.seconds() < 100.1);
}

// A backup whose target leaves the grid is the action's own reward, earned before it left,
// with no future: r(v, a) + gamma^t * 0 (problem.hpp's backup(); "future value 0 there,
// paper sec. 4.2", Discretizer::locate()). The corridor's own ways out of the grid earn
// nothing, so they cannot tell this reward from 0: a lunge, the punch taken while walking
// 0.5 m forward, lands its hit on a target 0.5 m ahead (gamma^3 on frame 3) and then
// leaves it at distance 0, off the grid.
TEST_CASE("a step that leaves the grid backs up its own reward and no future", "[learning]") {
  const ActionHit punch{0, 3, 1, 0.0f, 1.0f, 0.5f, 1.0f};
  const CorridorSetup parts(2, handModel(1, {{0, 0, 5, 0, 0.5, 0, {}}, {0, 0, 5, 0, -0.5, 0, {}},
                                             {0, 0, 5, 0, 0, 0, {punch}}, {0, 0, 5, 0, 0.5, 0, {punch}}}));
  const std::size_t lunge = 3, ahead = centre(*parts.grid, 0);
  const double gamma = 0.97, reward = std::pow(gamma, 3);  // the hit's weight is 1
  REQUIRE(parts.reward->gamma() == gamma);
  REQUIRE_FALSE(parts.grid->inside(parts.environment.next(parts.model, lunge, parts.grid->vertexState(ahead))));

  // Whatever the table holds, the backup is the reward alone, tabulated or compact.
  QTable q(parts.model, parts.tabulated.vertexCount);
  for (float& x : q.values()) x = 10.0f;
  const GridModel compact = GridModel::buildCompact(parts.problem, 1);
  CHECK(parts.tabulated.at(lunge, ahead).cell < 0);
  CHECK(backup(q, parts.tabulated, lunge, ahead) == Approx(reward).epsilon(1e-6));
  CHECK(backup(q, compact, lunge, ahead) == Approx(reward).epsilon(1e-6));

  // And so it converges in value iteration; one vertex further out the same lunge misses
  // (0.5 m short), lands on the grid and backs up only the future: gamma^5 times the best
  // there, punching in place forever (the corridor's v0).
  const TrainResult vi = trainWith("{type: value_iteration, tolerance: 1e-7}", parts.problem, parts.tabulated);
  REQUIRE(vi.stats["converged"] == true);
  const double v0 = reward / (1 - std::pow(gamma, 5));
  CHECK(vi.table.at(lunge, ahead) == Approx(reward).epsilon(1e-5));
  CHECK(vi.table.at(lunge, centre(*parts.grid, 1)) == Approx(std::pow(gamma, 5) * v0).epsilon(1e-5));
}

TEST_CASE("Q-learning's greedy policy converges to value iteration's on the corridor", "[learning]") {
  const CorridorSetup parts(2);
  const Problem& problem = parts.problem;
  const GridModel& g = parts.tabulated;
  const TrainResult vi = trainWith("{type: value_iteration, tolerance: 1e-7}", problem, g);
  const TrainResult q = trainWith("{type: q_learning, budget: 400000, seed: 3, curve_points: 4}", problem, g);
  REQUIRE(q.updates == 400000);
  REQUIRE(q.curve.size() == 4);
  // The corridor is deterministic, so Q-learning at alpha near 1 backs values up exactly:
  // the residual reaches float round-off.
  REQUIRE(q.curve.back().residual <= q.curve.front().residual);
  REQUIRE(q.finalResidual < 1e-5);
  std::size_t compared = 0, agree = 0;
  for (std::size_t v = 0; v < g.vertexCount; ++v) {
    std::array<float, 3> best{vi.table.at(0, v), vi.table.at(1, v), vi.table.at(2, v)};
    std::array<float, 3> learned{q.table.at(0, v), q.table.at(1, v), q.table.at(2, v)};
    const auto viBest = std::max_element(best.begin(), best.end()) - best.begin();
    std::array<float, 3> sorted = best;
    std::sort(sorted.begin(), sorted.end());
    if (sorted[2] - sorted[1] < 1e-3) continue;  // no clear best action
    ++compared;
    agree += (std::max_element(learned.begin(), learned.end()) - learned.begin()) == viBest;
  }
  CAPTURE(compared, agree);
  REQUIRE(compared >= 12);
  REQUIRE(agree == compared);
  // On the centre line the values themselves are close.
  for (int k = 0; k < 6; ++k)
    REQUIRE(q.table.at(k == 0 ? 2 : 0, centre(*parts.grid, k)) ==
            Approx(vi.table.at(k == 0 ? 2 : 0, centre(*parts.grid, k))).epsilon(0.05));
}

namespace {

// Checkpoints kept in memory; optionally "crashes" (throws) after a number of saves.
class MemoryCheckpointer final : public Checkpointer {
 public:
  explicit MemoryCheckpointer(int crashAfter) : crashAfter_(crashAfter) {}
  void save(const nlohmann::json& state, const QTable& table) override {
    state_ = state;
    table_ = table;
    ++saves;
    if (crashAfter_ > 0 && saves == crashAfter_) throw std::runtime_error("simulated crash");
  }
  std::optional<nlohmann::json> load(QTable& table) override {
    if (state_.is_null()) return std::nullopt;
    table = table_;
    return state_;
  }
  int saves = 0;
  nlohmann::json& state() { return state_; }

 private:
  int crashAfter_;
  nlohmann::json state_;
  QTable table_;
};

}  // namespace

// Three states with turning walks and an approach reward on a polar grid: interpolation
// is inexact here, so a short run is still far from converged and every update matters.
StateActionModel ring() {
  return handModel(3, {{0, 1, 7, 0.1, 0.3, 0.4, {}},
                       {0, 2, 9, -0.2, 0.1, -0.9, {}},
                       {1, 2, 5, 0.0, 0.4, 0.2, {}},
                       {1, 0, 11, 0.3, -0.1, 1.3, {}},
                       {2, 0, 6, -0.1, 0.5, -0.3, {}},
                       {2, 1, 8, 0.05, 0.2, 2.1, {}}});
}

// The ring's approach problem with a small checkpointed Q-learning run, for the resume and
// checkpoint tests.
struct RingSetup {
  RingSetup()
      : model(ring()),
        grid(makeGrid("{type: polar2d, radius: 2, rings: 5, sectors: 13}", model)),
        reward(app::plugins().rewards.create(yaml("{type: approach}"))),
        problem{model, *grid, *reward, environment},
        tabulated(GridModel::build(problem, 1)) {}
  StateActionModel model;
  std::unique_ptr<Discretizer> grid;
  std::unique_ptr<Reward> reward;
  StaticTarget environment;
  Problem problem;
  GridModel tabulated;
  RingSetup(const RingSetup&) = delete;  // problem refers to the members
  RingSetup& operator=(const RingSetup&) = delete;
};
constexpr const char* kRingLearner =
    "{type: q_learning, budget: 2000, seed: 9, checkpoint_every: 600, curve_points: 4}";

namespace {

// An avatar that stands still, punching in place: two states, four actions, no ground
// motion, so the target never leaves the grid.
StateActionModel standing() {
  const ActionHit punch{0, 3, 1, 0.0f, 1.0f, 0.5f, 1.0f};
  return handModel(2, {{0, 1, 5, 0, 0, 0, {punch}}, {0, 0, 5, 0, 0, 0, {}}, {1, 0, 5, 0, 0, 0, {}}, {1, 1, 5, 0, 0, 0, {punch}}});
}

}  // namespace

// The paper restarts Q-learning's walk only when the target leaves the grid. On a
// capture whose avatar hardly travels the target never leaves, one episode takes the whole
// budget and the walk stays in the first target's cell. max_episode_actions restarts it
// anyway; left at 0 it changes nothing (and no behaviour key: tables trained before it
// keep theirs).
TEST_CASE("Q-learning's episode cap restores coverage where the avatar stands still", "[learning]") {
  const CorridorSetup parts(2, standing());
  const Problem& problem = parts.problem;
  const GridModel& g = parts.tabulated;

  const TrainResult paper = trainWith("{type: q_learning, budget: 20000, seed: 4, curve_points: 2}", problem, g);
  CHECK(paper.stats["restarts"] == 1);  // one episode for the whole budget
  CHECK(paper.stats["cells_visited"] == 1);
  const TrainResult capped =
      trainWith("{type: q_learning, budget: 20000, seed: 4, curve_points: 2, max_episode_actions: 20}", problem, g);
  CHECK(capped.stats["restarts"].get<std::uint64_t>() >= 1000);
  CHECK(capped.stats["cell_coverage"].get<double>() > 0.95);
  // Coverage is what lets the values spread: more vertices hold a learned value.
  auto nonZero = [](const QTable& q) {
    return std::count_if(q.values().begin(), q.values().end(), [](float x) { return x != 0.0f; });
  };
  CHECK(nonZero(capped.table) > 4 * nonZero(paper.table));
  // A cap longer than the budget is the paper's rule: the same table.
  CHECK(trainWith("{type: q_learning, budget: 20000, seed: 4, curve_points: 2, max_episode_actions: 100000}", problem, g)
            .table == paper.table);

  // The cap is part of a table's key only when it is set.
  BehaviorSpec spec{"hit", "", 1, Activation::Always, yaml("{}"), yaml(kCorridorGrid), yaml("{type: hit}"),
                    ConfigNode::parse("", "none"), yaml("{type: q_learning}")};
  const std::string plain = behaviorConfigAndKey(spec, app::plugins(), "graph").second;
  spec.learner = yaml("{type: q_learning, max_episode_actions: 0}");
  CHECK(behaviorConfigAndKey(spec, app::plugins(), "graph").second == plain);
  spec.learner = yaml("{type: q_learning, max_episode_actions: 50}");
  CHECK(behaviorConfigAndKey(spec, app::plugins(), "graph").second != plain);
}

TEST_CASE("Q-learning is deterministic and a resumed run ends with the uninterrupted table", "[learning]") {
  const RingSetup setup;
  const Problem& problem = setup.problem;
  const GridModel& g = setup.tabulated;
  const std::string learner = kRingLearner;
  const TrainResult whole = trainWith(learner, problem, g);
  REQUIRE(whole.finalResidual > 1e-3);  // still learning: the comparisons below mean something
  REQUIRE(trainWith(learner, problem, g).table == whole.table);
  REQUIRE_FALSE(trainWith("{type: q_learning, budget: 2000, seed: 10}", problem, g).table == whole.table);
  // One thread walks and updates in turn; two walk the next chunk while updating this one.
  const std::string oneThread =
      "{type: q_learning, budget: 2000, seed: 9, checkpoint_every: 600, curve_points: 4, threads: 1}";
  REQUIRE(trainWith(oneThread, problem, g).table == whole.table);

  MemoryCheckpointer store(2);
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &store), "simulated crash");
  REQUIRE(store.saves == 2);
  MemoryCheckpointer resumed = store;  // continue from the second checkpoint (1200 actions)
  const TrainResult finished = trainWith(learner, problem, g, &resumed);
  REQUIRE(finished.stats["resumed"] == true);
  REQUIRE(resumed.saves == 3);  // one more, at 1800
  REQUIRE(finished.updates == 2000);
  REQUIRE(finished.table == whole.table);
  REQUIRE(finished.curve.size() == whole.curve.size());
  REQUIRE(finished.curve.back().residual == whole.curve.back().residual);
}

// Found by the kill tests (scripts/kill_test.py): a run resumed after a kill ended with the
// uninterrupted table but reported the coverage of the walk after the resume only (boxing's
// hit: 1422 cells visited of 1425 against 1425), as if the cells walked before the kill had
// never been. The checkpoint keeps the cells seen; every statistic but `resumed` is the
// uninterrupted run's.
TEST_CASE("a resumed Q-learning run reports the whole walk's coverage, as an uninterrupted one does",
          "[learning][checkpoint]") {
  // An avatar that stands still: each 400-action episode stays in its target's cell, so
  // the cells walked before a checkpoint are not walked again after it.
  const CorridorSetup parts(2, standing());
  const Problem& problem = parts.problem;
  const GridModel& g = parts.tabulated;
  const std::string learner =
      "{type: q_learning, budget: 2000, seed: 4, checkpoint_every: 600, curve_points: 4, max_episode_actions: 400}";
  const TrainResult whole = trainWith(learner, problem, g);
  REQUIRE(whole.stats["cells_visited"].get<std::size_t>() > 2);
  for (const int crashAfter : {1, 2, 3}) {
    CAPTURE(crashAfter);
    MemoryCheckpointer store(crashAfter);
    REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &store), "simulated crash");
    const TrainResult finished = trainWith(learner, problem, g, &store);
    REQUIRE(finished.stats["resumed"] == true);
    REQUIRE(finished.table == whole.table);
    nlohmann::json stats = finished.stats, expected = whole.stats;
    stats.erase("resumed");
    expected.erase("resumed");
    CHECK(stats == expected);
  }
}

// The viewer's learn panel steps Q-learning one action at a time. It must be the
// paper's algorithm, not a look-alike: the same seed and budget end with q_learning's
// table bit for bit, and every step reports the update rule's own numbers. Both share
// backup() and the grid model, so each update is also recomputed here from the table
// before the step, by the rule as q_learning.cpp states it (Lee & Lee sec. 4.2):
//   Q(v, a) <- (1 - alpha) Q(v, a) + alpha (r(v, a) + gamma^t_a max_a' Q(e'_v, a')),
// e'_v the vertex moved along by the action, Q(e'_v, .) interpolated in its cell (0 off
// the grid), t_a the action's frames, alpha falling linearly from 1 over the budget.
TEST_CASE("Q-learning taken step by step is q_learning, and each step reports its update", "[learning][lesson]") {
  const RingSetup setup;
  const Problem& problem = setup.problem;
  const StateActionModel& m = setup.model;
  const TrainResult whole = trainWith("{type: q_learning, budget: 2000, seed: 9, curve_points: 4}", problem, setup.tabulated);
  // A step updates Q(., a) only, and no action of the ring ends where it starts, so the
  // look-ahead's actions (those leaving a's end state) never include a: every corner's
  // look-ahead reads the table as it was before the step, whatever the corners' order.
  for (std::size_t a = 0; a < m.actionCount(); ++a) REQUIRE(m.actionFrom[a] != m.actionTo[a]);
  QLearningSteps steps(problem, 2000, 9);
  REQUIRE(steps.restarts() == 1);
  QTable previous = steps.table();
  std::size_t restarts = 0, futures = 0;
  while (!steps.done()) {
    const QTable before = steps.table();
    const QStep step = steps.step();
    REQUIRE(step.vertices.size() == 4);  // a 2-D grid's cell
    CHECK(step.alpha == Approx(1.0 - static_cast<double>(step.update - 1) / 2000).epsilon(1e-6));
    REQUIRE(step.action >= setup.model.stateActionBegin[step.state]);
    REQUIRE(step.action < setup.model.stateActionBegin[step.state + 1]);
    CHECK(step.nextState == setup.model.actionTo[step.action]);
    double weights = 0;
    for (const QStepVertex& v : step.vertices) {
      weights += v.weight;
      CHECK(v.before == previous.at(step.action, v.vertex));
      CHECK(v.backup == Approx(v.reward + v.discount * v.future).margin(1e-6));
      CHECK(v.after == Approx(v.before + step.alpha * (v.backup - v.before)).margin(1e-6));
      CHECK(v.after == steps.table().at(step.action, v.vertex));
      if (!v.nextInside) CHECK(v.future == 0);
      futures += v.future != 0;
      previous.at(step.action, v.vertex) = static_cast<float>(v.after);

      // The same update from `before` alone, without the step's own numbers.
      const std::size_t a = step.action;
      const TargetState vertex = setup.grid->vertexState(v.vertex);
      const double reward = setup.reward->evaluate(m, a, vertex);
      GridCell landing;
      const bool inside = setup.grid->locate(setup.environment.next(m, a, vertex), landing);
      double future = 0;
      if (inside) {
        const Stencil stencil = setup.grid->stencil(landing);
        const std::uint32_t next = m.actionTo[a];
        future = -std::numeric_limits<double>::infinity();
        for (std::uint32_t b = m.stateActionBegin[next]; b < m.stateActionBegin[next + 1]; ++b) {
          double value = 0;
          for (int k = 0; k < stencil.size; ++k) value += stencil.weight[k] * before.at(b, stencil.vertex[k]);
          future = std::max(future, value);
        }
      }
      const double target = reward + std::pow(setup.reward->gamma(), static_cast<double>(m.actionLength(a))) * future;
      const double alpha = 1 - static_cast<double>(step.update - 1) / 2000;
      CAPTURE(step.update, a, v.vertex, reward, inside, future, target);
      CHECK(v.nextInside == inside);
      CHECK(v.after == Approx((1 - alpha) * before.at(a, v.vertex) + alpha * target).epsilon(1e-5).margin(1e-6));
    }
    CHECK(weights == Approx(1.0).margin(1e-5));
    restarts += step.restarted;
  }
  REQUIRE(futures > 0);  // later steps do look ahead into learned values
  REQUIRE(steps.restarts() == restarts + 1);
  REQUIRE(steps.touched() > 0);
  REQUIRE(steps.table() == whole.table);
  REQUIRE(steps.updates() == 2000);
  REQUIRE_THROWS_WITH(steps.step(), Catch::Contains("budget of 2000 actions is spent"));
  // Another seed walks elsewhere.
  QLearningSteps other(problem, 2000, 10);
  while (!other.done()) other.step();
  REQUIRE_FALSE(other.table() == whole.table);
}

namespace {

// Keeps what each snapshot showed: its point, the table's value sum and its grid.
class SnapshotRecorder final : public TrainObserver {
 public:
  explicit SnapshotRecorder(std::size_t wanted) : wanted_(wanted) {}
  std::size_t snapshotCount() const override { return wanted_; }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override {
    points.push_back(point);
    double sum = 0;
    for (float x : table.values()) sum += x;
    sums.push_back(sum);
    grids.push_back(grid);
  }
  std::vector<CurvePoint> points;
  std::vector<double> sums;
  std::vector<const Discretizer*> grids;

 private:
  std::size_t wanted_;
};

TrainResult trainObserved(const std::string& learnerYaml, const Problem& problem, const GridModel& g,
                          TrainObserver& observer) {
  return app::plugins().learners.create(yaml(learnerYaml))->train({problem, g, &observer, nullptr, 2});
}

}  // namespace

// Learning curves of success rate need the table along training. Learners hand
// out snapshots at about n evenly spaced points only to an observer that asks, and train
// the same table either way.
TEST_CASE("learners hand out snapshots along training and train the same table", "[learning]") {
  SECTION("q_learning: at budget * i / n, the last the final table") {
    const RingSetup setup;
    for (std::size_t n : {std::size_t{1}, std::size_t{3}, std::size_t{7}}) {
      CAPTURE(n);
      // curve_points 4 and checkpoint_every 600 do not line up with sevenths: chunks end at both.
      const TrainResult plain = trainWith(kRingLearner, setup.problem, setup.tabulated);
      SnapshotRecorder recorder(n);
      const TrainResult observed = trainObserved(kRingLearner, setup.problem, setup.tabulated, recorder);
      REQUIRE(observed.table == plain.table);
      REQUIRE(observed.curve.size() == plain.curve.size());
      for (std::size_t i = 0; i < plain.curve.size(); ++i) REQUIRE(observed.curve[i].residual == plain.curve[i].residual);
      REQUIRE(recorder.points.size() == n);
      for (std::size_t i = 0; i < n; ++i) {
        CHECK(recorder.points[i].updates == 2000 * (i + 1) / n);
        CHECK(recorder.points[i].residual > 0);
        CHECK(recorder.grids[i] == nullptr);
        if (i > 0) CHECK(recorder.points[i].seconds >= recorder.points[i - 1].seconds);
      }
      double sum = 0;
      for (float x : plain.table.values()) sum += x;
      CHECK(recorder.sums.back() == sum);
      // At a curve point (2000 * 1 / 1 = the last of 4) its residual is the curve's.
      if (n == 1) CHECK(recorder.points.back().residual == plain.curve.back().residual);
    }
    // Nobody listening (snapshotCount() 0): no snapshot.
    SnapshotRecorder none(0);
    trainObserved(kRingLearner, setup.problem, setup.tabulated, none);
    CHECK(none.points.empty());
  }
  SECTION("value_iteration: about n of its sweeps, the last one always") {
    const CorridorSetup parts(2);
    const std::string learner = "{type: value_iteration, tolerance: 1e-7}";
    const TrainResult plain = trainWith(learner, parts.problem, parts.tabulated);
    const std::size_t sweeps = plain.stats["sweeps"].get<std::size_t>();
    REQUIRE(sweeps >= 20);
    SnapshotRecorder recorder(5);
    const TrainResult observed = trainObserved(learner, parts.problem, parts.tabulated, recorder);
    REQUIRE(observed.table == plain.table);
    CAPTURE(sweeps, recorder.points.size());
    CHECK(recorder.points.size() >= 3);
    CHECK(recorder.points.size() <= 8);
    CHECK(recorder.points.back().updates == plain.updates);
    CHECK(recorder.points.back().residual == plain.curve.back().residual);
    for (std::size_t i = 1; i < recorder.points.size(); ++i) CHECK(recorder.points[i].updates > recorder.points[i - 1].updates);
  }
}

// state.json was trusted as it stood. One changed digit of the update
// count or of the generator resumed a different run without a word, and a missing,
// mistyped or out-of-range member aborted training. Now the checkpoint's hash and the
// learner's own reading of its state both reject it, the run says so and starts over.
TEST_CASE("Q-learning reports a damaged or invalid checkpoint, ignores it and trains from the start",
          "[learning][checkpoint]") {
  using nlohmann::json;
  const RingSetup setup;
  const StateActionModel& m = setup.model;
  const Problem& problem = setup.problem;
  const GridModel& g = setup.tabulated;
  const std::string learner = kRingLearner;
  const TrainResult clean = trainWith(learner, problem, g);

  test::TempDir tmp("learning-checkpoint-test");
  const std::filesystem::path dir = tmp.path / "checkpoint", statePath = dir / "state.json";
  std::vector<std::string> log;
  DirectoryCheckpointer store(dir, "run-key", m, g.vertexCount, [&](const std::string& line) { log.push_back(line); });
  REQUIRE(trainWith(learner, problem, g, &store).table == clean.table);
  REQUIRE(log.empty());
  // The learner leaves its last checkpoint (the application removes it after a finished
  // run): a resume from it at 1800 actions.
  const std::string text = readFile(statePath);
  json saved = json::parse(text);
  REQUIRE(saved["state"]["updates"] == 1800);
  REQUIRE(saved["state"]["walk"]["updates"] == 1800);
  REQUIRE(m.stateCount() == 3);
  // A hand edit that also fixes the hash: only the learner's own checks can catch it.
  auto sealed = [](json j) {
    j["hash"] = manifestHash(j);
    return j.dump(2);
  };
  const std::string hashMismatch = "state.json: expected its members to hash to '";

  std::string damaged, message;
  SECTION("a changed digit of the update count") {
    damaged = text;
    const std::size_t at = damaged.rfind("\"updates\": 1800");  // the walk's
    REQUIRE(at != std::string::npos);
    damaged[at + 12] = '2';  // 1800 -> 1200
    message = hashMismatch;
  }
  SECTION("a changed word of the random generator") {
    json j = saved;
    j["state"]["walk"]["rng"][1] = j["state"]["walk"]["rng"][1].get<std::uint64_t>() ^ 1;
    damaged = j.dump(2);
    message = hashMismatch;
  }
  SECTION("a missing member") {
    json j = saved;
    j["state"]["walk"].erase("restarts");
    damaged = sealed(j);
    message = "state.json: state.walk: expected the key 'restarts', found none";
  }
  SECTION("a member of the wrong type") {
    json j = saved;
    j["state"]["walk"]["state"] = "2";
    damaged = sealed(j);
    message = "state.json: state.walk.state: expected an integer in [0, 2], found '\"2\"'";
  }
  SECTION("a state out of range") {
    json j = saved;
    j["state"]["walk"]["state"] = 3;
    damaged = sealed(j);
    message = "state.json: state.walk.state: expected an integer in [0, 2], found '3'";
  }
  SECTION("an update count past the budget") {
    json j = saved;
    j["state"]["updates"] = j["state"]["walk"]["updates"] = 2400;
    damaged = sealed(j);
    message = "state.json: state.walk.updates: expected an integer in [0, 2000], found '2400'";
  }
  SECTION("update counts that disagree") {
    json j = saved;
    j["state"]["updates"] = 1200;
    damaged = sealed(j);
    message = "state.json: state.updates: expected 1800, as state.walk.updates, found '1200'";
  }
  SECTION("a generator stuck at zero") {
    json j = saved;
    j["state"]["walk"]["rng"] = {0, 0, 0, 0};
    damaged = sealed(j);
    message = "state.json: state.walk.rng: expected a generator state other than all zeros, found '[0,0,0,0]'";
  }
  SECTION("a target that is not 3 numbers") {
    json j = saved;
    j["state"]["walk"]["target"] = {0.5, 1};
    damaged = sealed(j);
    message = "state.json: state.walk.target: expected 3 finite numbers, found '[0.5,1]'";
  }
  SECTION("a curve point past the walk") {
    json j = saved;
    j["state"]["curve"][0][0] = 1900;
    damaged = sealed(j);
    message = "state.json: state.curve[0][0]: expected an update count in [1, 1800]";
  }
  SECTION("cells seen that do not fit the grid") {
    json j = saved;
    j["state"]["cells_seen"] = "ff";
    damaged = sealed(j);
    message = "state.json: state.cells_seen: expected 13 lowercase hex digits, one bit per grid cell of 52, found '\"ff\"'";
  }
  SECTION("cells seen in other than lowercase hex digits") {
    json j = saved;
    std::string seen = j["state"]["cells_seen"];
    seen[0] = 'F';
    j["state"]["cells_seen"] = seen;
    damaged = sealed(j);
    message = "state.json: state.cells_seen: expected 13 lowercase hex digits, one bit per grid cell of 52";
  }
  SECTION("a state that is not an object") {
    json j = saved;
    j["state"] = 5;
    damaged = sealed(j);
    message = "state.json: state: expected an object, found '5'";
  }
  CAPTURE(message);
  writeFileAtomically(statePath, damaged);
  log.clear();
  TrainResult resumed;
  REQUIRE_NOTHROW(resumed = trainWith(learner, problem, g, &store));
  CHECK(resumed.stats["resumed"] == false);
  CHECK(resumed.updates == 2000);
  CHECK(resumed.table == clean.table);  // nothing of the checkpoint, the table included
  CHECK(resumed.curve.size() == clean.curve.size());
  REQUIRE(log.size() == 1);
  CHECK(log[0].rfind(statePath.string(), 0) == 0);  // names the file first
  CHECK_THAT(log[0], Catch::Contains(message));
  CHECK_THAT(log[0], Catch::EndsWith("; ignoring the checkpoint"));
}

TEST_CASE("Q-learning resumes an intact directory checkpoint to the uninterrupted table", "[learning][checkpoint]") {
  const RingSetup setup;
  const StateActionModel& m = setup.model;
  const Problem& problem = setup.problem;
  const GridModel& g = setup.tabulated;
  const std::string learner = kRingLearner;
  const TrainResult clean = trainWith(learner, problem, g);
  test::TempDir tmp("learning-checkpoint-test");
  std::vector<std::string> log;
  DirectoryCheckpointer store(tmp.path / "checkpoint", "run-key", m, g.vertexCount,
                              [&](const std::string& line) { log.push_back(line); });
  trainWith(learner, problem, g, &store);
  const TrainResult resumed = trainWith(learner, problem, g, &store);  // from 1800 actions
  CHECK(log.empty());
  CHECK(resumed.stats["resumed"] == true);
  CHECK(resumed.table == clean.table);
  CHECK(resumed.curve.size() == clean.curve.size());
}

// Found by the kill tests (scripts/kill_test.py): `train` killed while replacing a checkpoint
// leaves the new one in `<dir>.tmp-PID-N` beside the old. The next run without --resume
// removed the checkpoint to start over, and the learner's load then put the killed run's
// temporary back in its place (recovery of a missing bundle) and continued from it:
// "resume: approach: continuing from the checkpoint" in a run that asked to start over.
// remove() now removes what killed writers left beside the checkpoint too.
TEST_CASE("a removed checkpoint stays removed, whatever a killed writer left beside it", "[learning][checkpoint]") {
  const RingSetup setup;
  const StateActionModel& m = setup.model;
  const GridModel& g = setup.tabulated;
  test::TempDir tmp("learning-checkpoint-remove");
  const std::filesystem::path dir = tmp.path / "checkpoint";
  std::vector<std::string> log;
  DirectoryCheckpointer store(dir, "run-key", m, g.vertexCount, [&](const std::string& line) { log.push_back(line); });
  trainWith(kRingLearner, setup.problem, g, &store);  // leaves its last checkpoint
  REQUIRE(std::filesystem::exists(dir / "state.json"));
  // A process that is gone, killed with a whole checkpoint in its temporary.
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  int status = 0;
  ::waitpid(gone, &status, 0);
  const std::filesystem::path leftover = tmp.path / fmt::format("checkpoint.tmp-{}-0", gone);
  std::filesystem::copy(dir, leftover);

  store.remove();
  CHECK_FALSE(std::filesystem::exists(dir));
  CHECK_FALSE(std::filesystem::exists(leftover));
  QTable table(m, g.vertexCount);
  CHECK_FALSE(store.load(table).has_value());
  CHECK(std::filesystem::is_empty(tmp.path));
  CHECK(log.empty());
}

TEST_CASE("a checkpointer that cannot report refuses a state the learner rejects", "[learning][checkpoint]") {
  const RingSetup setup;
  const Problem& problem = setup.problem;
  const GridModel& g = setup.tabulated;
  const std::string learner = kRingLearner;
  MemoryCheckpointer store(2);
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &store), "simulated crash");
  MemoryCheckpointer broken = store;
  broken.state()["walk"]["state"] = 7;
  REQUIRE_THROWS_AS(trainWith(learner, problem, g, &broken), Error);
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &broken),
                      "checkpoint: state.walk.state: expected an integer in [0, 2], found '7'");
}

TEST_CASE("the combined controller takes the best weighted sum of active behaviours", "[learning]") {
  const CorridorSetup parts(1);
  const StateActionModel& m = parts.model;
  const Problem& problem = parts.problem;
  const GridModel& g = parts.tabulated;
  const TrainResult vi = trainWith("{type: value_iteration, tolerance: 1e-7}", problem, g);
  PolicyController controller(m, {{parts.grid.get(), &vi.table, 1.0, Activation::TargetInside}});
  REQUIRE(controller.choose(0, {0, 1, 0.5}) == 2);  // punch at 0.5 m
  REQUIRE(controller.choose(0, {0, 1, 2.0}) == 0);  // walk forward from 2 m
  // Outside the grid the target_inside behaviour is silent: all scores 0, first action.
  REQUIRE(controller.choose(0, {0, 1, 5.0}) == 0);
  REQUIRE(std::vector<float>(controller.scores().begin(), controller.scores().end()) == std::vector<float>{0, 0, 0});
  // A negative weight turns the preference around.
  PolicyController contrary(m, {{parts.grid.get(), &vi.table, -1.0, Activation::Always}});
  REQUIRE(contrary.choose(0, {0, 1, 2.0}) == 1);
}

TEST_CASE("the online search baseline finds the corridor's best first action within its horizon", "[learning]") {
  // The corridor with its actions in another order, so that the tie rule (lowest index)
  // cannot pass for a good choice: 0 walks back, 1 walks forward, 2 punches.
  const ActionHit punch{0, 3, 1, 0.0f, 1.0f, 0.5f, 1.0f};
  const StateActionModel m =
      handModel(1, {{0, 0, 5, 0, -0.5, 0, {}}, {0, 0, 5, 0, 0.5, 0, {}}, {0, 0, 5, 0, 0, 0, {punch}}});
  Built parts = corridorParts(m);
  const std::vector<SearchPart> search{{parts.grid.get(), parts.reward.get(), 1.0, Activation::Always}};
  // 2 m away the punch position is 3 walks ahead: a horizon of 4 sees the punch, and only
  // walking forward first leads there.
  OnlineSearchController deep(m, parts.environment, search, 4, 0.97);
  REQUIRE(deep.choose(0, {0, 1, 2.0}) == 1);
  REQUIRE(deep.expanded() == 3 + 9 + 27 + 81);
  // A horizon of 2 sees nothing rewarding from 2 m: every sequence is worth 0 and the tie
  // goes to the first action, walking away; from 1 m it sees walk-then-punch.
  OnlineSearchController shallow(m, parts.environment, search, 2, 0.97);
  REQUIRE(shallow.choose(0, {0, 1, 2.0}) == 0);
  REQUIRE(shallow.choose(0, {0, 1, 1.0}) == 1);
  // At 0.5 m the punch wins at any depth.
  for (int horizon = 1; horizon <= 4; ++horizon) {
    OnlineSearchController any(m, parts.environment, search, horizon, 0.97);
    REQUIRE(any.choose(0, {0, 1, 0.5}) == 2);
  }
}

// --- The reward vocabulary and success criteria (scenarios/README.md, "reward terms") ---

// The tiny action model of "rewards match hand-computed values" plus a right-foot kick at
// frame 3 of the walk, its toe 0.2 m left, 0.9 m up and 0.7 m ahead, weight 0.8.
namespace {
StateActionModel kickingModel() {
  const ActionHit hit{0, 2, 1, 0.0f, 1.3f, 0.6f, 0.5f};
  StateActionModel m = handModel(1, {{0, 0, 4, 0, 0.4, 0, {hit}}, {0, 0, 4, 0, 0, 0, {}}});
  m.kicks.push_back({0, 3, 1, 0.2f, 0.9f, 0.7f, 0.8f});
  m.actionKickBegin = {0, 1, 1};
  m.maxKickSpeed_mps = 5;
  return m;
}

double termsReward(const StateActionModel& m, const std::string& block, std::size_t a, const Eigen::Vector3d& e) {
  return app::plugins().rewards.create(yaml(block))->evaluate(m, a, e);
}
}  // namespace

TEST_CASE("a reward naming a joint is not evaluated before it is bound to a model with joints", "[learning][terms]") {
  StateActionModel m = kickingModel();  // made by hand: no joints recorded
  const Eigen::Vector3d e(0, 1, 0.5);
  const auto head = app::plugins().rewards.create(yaml("{type: terms, terms: [{term: distance, point: head}]}"));
  CHECK_THROWS_AS(head->evaluate(m, 0, e), std::logic_error);
  CHECK_THROWS_WITH(head->bind(m), Catch::Contains("no joint 'head': this model records no skeleton joints"));
  // Bound to one skeleton, evaluated on a model of another: refused, not read past the arrays.
  m.jointNames = {"Head"};
  m.roleJoint.assign(roleNames().size(), 0);
  m.sourceJoint.assign(3 * m.framesTotal, 0.5f);
  m.sourceJointSpeed.assign(m.framesTotal, 1.0f);
  head->bind(m);
  CHECK(head->evaluate(m, 0, e) > 0);
  StateActionModel other = m;
  other.jointNames = {"Head", "Neck"};
  other.sourceJoint.assign(6 * m.framesTotal, 0.5f);
  other.sourceJointSpeed.assign(2 * m.framesTotal, 1.0f);
  CHECK_THROWS_AS(head->evaluate(other, 0, e), std::logic_error);
  // Terms without joints need no binding.
  CHECK(termsReward(m, "{type: terms, terms: [{term: distance, point: pelvis}]}", 0, e) > 0);
}

TEST_CASE("a terms reward of one distance or contact term is the paper's approach or hit", "[learning][terms]") {
  const StateActionModel m = kickingModel();
  const auto approach = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.1, gamma: 0.9}"));
  const auto distance = app::plugins().rewards.create(yaml("{type: terms, gamma: 0.9, terms: [{term: distance, sigma: 0.1}]}"));
  const auto hit = app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.1, gamma: 0.9}"));
  const auto contact = app::plugins().rewards.create(yaml("{type: terms, gamma: 0.9, terms: [{term: contact, radius: 0.1}]}"));
  Rng rng(7);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d e(rng.uniform() - 0.5, 1 + 0.6 * rng.uniform(), rng.uniform());
    for (std::size_t a = 0; a < 2; ++a) {
      CAPTURE(i, a);
      CHECK(distance->evaluate(m, a, e) == Approx(approach->evaluate(m, a, e)).epsilon(1e-12));
      CHECK(contact->evaluate(m, a, e) == Approx(hit->evaluate(m, a, e)).epsilon(1e-12));
    }
  }
  CHECK(contact->evaluate(m, 0, {0, 1.3, 0.6}) == Approx(0.81 * 0.5));  // the punch lands
}

TEST_CASE("each reward term gives its hand-computed value", "[learning][terms]") {
  const StateActionModel m = kickingModel();  // action 0 walks 0.1 m a frame, action 1 stands
  const double g = 0.9;
  SECTION("distance with a preferred distance, max and sum") {
    // Standing with the target 1 m ahead of the pelvis: the signal is 1 at every frame.
    const std::string keep = "{type: terms, gamma: 0.9, terms: [{term: distance, point: pelvis, d0: 1, sigma: 0.2}]";
    CHECK(termsReward(m, keep + "}", 1, {0, 0, 1}) == Approx(g));
    CHECK(termsReward(m, keep + ", combine: sum}", 1, {0, 0, 1}) == Approx(g + g * g + g * g * g + g * g * g * g));
    // 1.2 m away: exp(-0.2 / 0.2) at every frame.
    CHECK(termsReward(m, keep + "}", 1, {0, 0, 1.2}) == Approx(g * std::exp(-1.0)));
    // Walking toward a target 1.4 m ahead reaches 1 m from it at frame 4.
    CHECK(termsReward(m, keep + "}", 0, {0, 0, 1.4}) == Approx(g * g * g * g));
  }
  SECTION("facing with a preferred angle") {
    const Eigen::Vector3d left(1, 0, 0);  // 90 degrees to the avatar's left
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: facing, angle_deg: 90}]}", 1, left) == Approx(g));
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: facing, sigma_deg: 30}]}", 1, left) ==
          Approx(g * std::exp(-3.0)));
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: facing}]}", 1, {0, 0, 2}) == Approx(g));
  }
  SECTION("facing as the capture's own strikes stand to it (prefer: hits)") {
    // The model's strikes, at their frames: the punch straight ahead (0 degrees), the kick
    // at atan(0.2 / 0.4) = 26.6 degrees to the left. One sample each: two equal peaks.
    const std::string hits = "{type: terms, gamma: 0.9, terms: [{term: facing, prefer: hits, sigma_deg: 1}]}";
    auto bound = [&](const std::string& block, const Eigen::Vector3d& e) {
      const auto reward = app::plugins().rewards.create(yaml(block));
      reward->bind(m);
      return reward->evaluate(m, 1, e);  // standing: the angle is the same at every frame
    };
    auto at = [](double degrees) {  // 2 m away, that far to the left (negative: right)
      return Eigen::Vector3d(2 * std::sin(degrees * M_PI / 180), 0, 2 * std::cos(degrees * M_PI / 180));
    };
    CHECK(bound(hits, at(0)) == Approx(g));
    CHECK(bound(hits, at(27)) == Approx(g).epsilon(1e-3));
    CHECK(bound(hits, at(-27)) < 1e-6);  // signed: the kick landed to the left, not the right
    CHECK(bound(hits, at(90)) < 1e-6);
    CHECK(bound(hits, at(13.5)) < 1e-6);  // between the peaks, with a 1-degree kernel
    // A wider kernel fills the gap.
    CHECK(bound("{type: terms, gamma: 0.9, terms: [{term: facing, prefer: hits, sigma_deg: 20}]}", at(13.5)) > 0.5 * g);
    // Unbound, it refuses to answer instead of reading an empty table.
    const auto unbound = app::plugins().rewards.create(yaml(hits));
    CHECK_THROWS_AS(unbound->evaluate(m, 1, at(0)), std::logic_error);
    // A capture without strikes has no stance to learn: one error at the term.
    StateActionModel still = m;
    still.hits.clear();
    still.kicks.clear();
    still.actionHitBegin.assign(still.actionHitBegin.size(), 0);
    still.actionKickBegin.assign(still.actionKickBegin.size(), 0);
    const auto none = app::plugins().rewards.create(yaml(hits));
    CHECK_THROWS_WITH(none->bind(still), Catch::Contains("prefer: ") && Catch::Contains("found none"));
  }
  SECTION("facing as the real bouts' fighters stand to each other (prefer: bouts)") {
    // A data folder of one SNU-named bout made from tests/data/stats/stand: fighter 2 faces
    // fighter 1 (0 degrees), fighter 1 is turned 60 degrees away, for 30 frames each. The
    // density counts each unsigned sample at both signs: 60 samples at 0, 30 at +60 and 30
    // at -60, so 0 degrees gives 1 and 60 degrees either way 0.5.
    const mgrl::test::TempDir data("facing_bouts");
    const std::filesystem::path motion = data.path / "snu_martial_arts" / "motion";
    std::filesystem::create_directories(motion);
    const std::filesystem::path stand = mgrl::test::testData() / "stats" / "stand";
    std::string turned = readFile(stand / "fighter_1.bvh");
    for (std::size_t at = turned.find("0 95 0 0 0 0"); at != std::string::npos; at = turned.find("0 95 0 0 0 0", at))
      turned.replace(at, 12, "0 95 0 60 0 0");
    writeFileAtomically(motion / "s_001_1_1.bvh", turned);
    writeFileAtomically(motion / "s_001_1_2.bvh", readFile(stand / "fighter_2.bvh"));
    // The data folder a scenario would have recorded, put back however the section ends.
    struct Recorded {
      explicit Recorded(const std::filesystem::path& dir) { recordScenarioDataDirectory(dir); }
      ~Recorded() { recordScenarioDataDirectory({}); }
      Recorded(const Recorded&) = delete;
      Recorded& operator=(const Recorded&) = delete;
    };
    std::optional<Recorded> recorded;
    recorded.emplace(data.path);
    const std::string bouts = "{type: terms, gamma: 0.9, terms: [{term: facing, prefer: bouts, sigma_deg: 1}]}";
    auto bound = [&](const std::string& block, const Eigen::Vector3d& e) {
      const auto reward = app::plugins().rewards.create(yaml(block));
      reward->bind(m);
      return reward->evaluate(m, 1, e);  // standing: the angle is the same at every frame
    };
    auto at = [](double degrees) {
      return Eigen::Vector3d(2 * std::sin(degrees * M_PI / 180), 0, 2 * std::cos(degrees * M_PI / 180));
    };
    CHECK(bound(bouts, at(0)) == Approx(g));
    CHECK(bound(bouts, at(60)) == Approx(0.5 * g).epsilon(1e-3));
    CHECK(bound(bouts, at(-60)) == Approx(0.5 * g).epsilon(1e-3));
    CHECK(bound(bouts, at(30)) < 1e-6);
    CHECK(bound(bouts, at(120)) < 1e-6);
    // Stances (prefer: stance): the 60 samples cut in two equally large parts, 30 at 0
    // degrees and 30 at 60: stance 0 prefers 0 degrees, stance 1 60, as angle_deg would.
    auto stance = [](int k, int of) {
      return fmt::format(
          "{{type: terms, gamma: 0.9, terms: [{{term: facing, prefer: stance, stance: {}, stances: {}, "
          "sigma_deg: 30}}]}}",
          k, of);
    };
    CHECK(bound(stance(1, 2), at(60)) == Approx(g));
    CHECK(bound(stance(1, 2), at(-60)) == Approx(g));
    CHECK(bound(stance(1, 2), at(0)) == Approx(g * std::exp(-2.0)));
    CHECK(bound(stance(0, 2), at(0)) == Approx(g));
    CHECK(bound(stance(0, 1), at(30)) == Approx(g));  // one part: the median of 0 and 60
    CHECK_THROWS_WITH(app::plugins().rewards.create(yaml(stance(2, 2))),
                      Catch::Contains("stance") && Catch::Contains("expected a stance below stances (2), found 2"));
    // A data folder without the SNU capture: one error at the term's key.
    const mgrl::test::TempDir empty("facing_bouts_none");
    recorded.reset();
    recorded.emplace(empty.path);
    const auto none = app::plugins().rewards.create(yaml(bouts));
    CHECK_THROWS_WITH(none->bind(m), Catch::Contains("prefer: ") &&
                                         Catch::Contains("expected the SNU sparring capture s_TTT_K_P.bvh in"));
    const auto noStance = app::plugins().rewards.create(yaml(stance(0, 2)));
    CHECK_THROWS_WITH(noStance->bind(m), Catch::Contains("prefer: stance: ") &&
                                             Catch::Contains("expected the SNU sparring capture s_TTT_K_P.bvh in"));
  }
  SECTION("contact by a chosen effector") {
    const Eigen::Vector3d kick(0.2, 0.9, 0.7), punch(0, 1.3, 0.6);
    const std::string feet = "{type: terms, gamma: 0.9, terms: [{term: contact, effector: feet, radius: 0.1}]}";
    CHECK(termsReward(m, feet, 0, kick) == Approx(g * g * g * 0.8));
    CHECK(termsReward(m, feet, 0, punch) == 0);
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: contact, effector: right_foot, radius: 0.1}]}", 0,
                      kick) == Approx(g * g * g * 0.8));
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: contact, effector: left_foot, radius: 0.1}]}", 0,
                      kick) == 0);
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: contact, effector: fists, radius: 0.1}]}", 0,
                      kick) == 0);
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: contact, effector: any, radius: 0.1}]}", 0,
                      punch) == Approx(g * g * 0.5));
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: contact, effector: feet, radius: 0.1, "
                         "use_speed: false}]}",
                      0, kick) == Approx(g * g * g));
  }
  SECTION("travel toward or away, effort") {
    // 0.1 m of progress a frame toward a target 2 m ahead, full signal at 0.4 m (frame 4).
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: travel, scale_m: 0.4}]}", 0, {0, 0, 2}) ==
          Approx(g * g * g * g));
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: travel, direction: away}]}", 0, {0, 0, 2}) == 0);
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: travel, direction: away, scale_m: 0.4}]}", 0,
                      {0, 0, -2}) == Approx(g * g * g * g));
    // 0.1 m a frame at 30 fps is 3 m/s.
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: effort, speed_mps: 3}]}", 0, {0, 0, 2}) ==
          Approx(g * std::exp(-1.0)));
    CHECK(termsReward(m, "{type: terms, gamma: 0.9, terms: [{term: effort, speed_mps: 3}]}", 1, {0, 0, 2}) == Approx(g));
  }
  SECTION("reversal: a cost at each frame that steps against the direction of travel") {
    const std::string cost = "{type: terms, gamma: 0.9, combine: sum, terms: [{term: reversal}]}";
    const auto reward = [&](const StateActionModel& model, std::size_t a) {
      const auto r = app::plugins().rewards.create(yaml(cost));
      r->bind(model);
      return r->evaluate(model, a, TargetState{Eigen::Vector3d(0, 0, 2)});
    };
    // Walking on in the direction it arrived with (action 0 ends on the state it leaves),
    // or standing: nothing to pay.
    CHECK(reward(m, 0) == 0);
    CHECK(reward(m, 1) == 0);
    // Two steps forward, two back: the third frame turns back (the fourth goes on the new
    // way), and the first now turns back on the arrival, which ends going back.
    StateActionModel back = m;
    back.frameRoot[3 * 2 + 1] = 0.1;
    back.frameRoot[3 * 3 + 1] = 0.0;
    CHECK(reward(back, 0) == Approx(-(g + g * g * g)));
    // Steps slower than min_speed_mps neither pay nor turn: 0.1 m a frame is 3 m/s.
    const auto slow = app::plugins().rewards.create(
        yaml("{type: terms, gamma: 0.9, combine: sum, terms: [{term: reversal, min_speed_mps: 4}]}"));
    slow->bind(back);
    CHECK(slow->evaluate(back, 0, TargetState{Eigen::Vector3d(0, 0, 2)}) == 0);
    // Bound to one model, evaluated on another: refused, not read past its frames.
    const auto bound = app::plugins().rewards.create(yaml(cost));
    bound->bind(m);
    StateActionModel longer = m;
    longer.actionFrames.push_back(0);
    CHECK_THROWS_AS(bound->evaluate(longer, 0, TargetState{Eigen::Vector3d(0, 0, 2)}), std::logic_error);
  }
  SECTION("weights add the terms' signals frame by frame") {
    const std::string both =
        "{type: terms, gamma: 0.9, terms: [{term: distance, point: pelvis, d0: 1, sigma: 0.2, weight: 2}, "
        "{term: facing, angle_deg: 90, weight: 0.5}]}";
    // Target 1 m to the left: distance signal 1 (weight 2), facing signal 1 (weight 0.5).
    CHECK(termsReward(m, both, 1, {1, 0, 0}) == Approx(g * 2.5));
  }
}

TEST_CASE("reward terms refuse bad YAML with the line, column and key", "[learning][terms]") {
  const auto build = [](const std::string& text) { return app::plugins().rewards.create(yaml(text)); };
  CHECK_THROWS_WITH(build("{type: terms}"), Catch::StartsWith("test.yaml:1:1: ") && Catch::Contains("expected a 'terms' list"));
  CHECK_THROWS_WITH(build("{type: terms, terms: []}"),
                    Catch::StartsWith("test.yaml:1:22: terms: ") && Catch::Contains("expected at least one term"));
  CHECK_THROWS_WITH(
      build("{type: terms, terms: [{term: dist}]}"),
      Catch::StartsWith("test.yaml:1:30: terms[0].term: ") &&
          Catch::Contains("unknown term 'dist' (known: distance, facing, contact, travel, effort, avoid, struck, "
                          "reversal)"));
  CHECK_THROWS_WITH(build("{type: terms, terms: [{term: distance, sigma: 0}]}"),
                    Catch::StartsWith("test.yaml:1:47: terms[0].sigma: "));
  CHECK_THROWS_WITH(build("{type: terms, terms: [{term: distance, point: pelvis, dims: 3}]}"),
                    Catch::Contains("terms[0].dims: expected 2 with point: pelvis"));
  CHECK_THROWS_WITH(build("{type: terms, terms: [{term: contact, effector: nose}]}"),
                    Catch::Contains("terms[0].effector: ") && Catch::Contains("left_foot"));
  CHECK_THROWS_WITH(build("{type: terms, terms: [{term: facing, d0: 1}]}"),
                    Catch::Contains("terms[0].d0: unknown key"));
  CHECK_THROWS_WITH(build("{type: terms, combine: mean, terms: [{term: facing}]}"),
                    Catch::Contains("combine: ") && Catch::Contains("max, sum"));
  CHECK_THROWS_WITH(
      build("{type: terms, terms: [facing]}"),
      Catch::Contains(
          "terms[0]: expected a map with 'term: <distance|facing|contact|travel|effort|avoid|struck|reversal>'"));
  CHECK_NOTHROW(build("{type: terms, terms: [{term: facing}]}"));
}

TEST_CASE("success criteria take what they leave out from the reward and hold for hold_s", "[learning][terms]") {
  const StateActionModel m = kickingModel();
  // The reward as terms (Reward::terms()), and the success terms the reward terms register.
  const nlohmann::json keep =
      nlohmann::json::array({{{"term", "distance"}, {"point", "pelvis"}, {"dims", 2}, {"d0", 1.0}, {"sigma", 0.2}}});
  const ConditionRegistry& kinds = app::plugins().conditions;
  SECTION("a distance held for 0.1 s (3 frames)") {
    const SuccessCriterion c = SuccessCriterion::read(yaml("{term: distance, within: 0.1, hold_s: 0.1}"), keep, kinds);
    REQUIRE(c.size() == 1);
    CHECK(c.toJson()["all"][0]["point"] == "pelvis");
    CHECK(c.toJson()["all"][0]["d0"] == 1.0);
    SuccessCriterion::Tracker near(c, m.frameTime), far(c, m.frameTime);
    CHECK(near.play(m, 1, {0, 0, 1.05}) == 3);
    CHECK(far.play(m, 1, {0, 0, 1.2}) == 0);
    CHECK(c.describe().find("pelvis") != std::string::npos);
  }
  SECTION("a reward term's value of the wrong kind is one clear error, not a JSON exception") {
    const nlohmann::json wrong = nlohmann::json::array({{{"term", "distance"}, {"d0", "far"}}});
    REQUIRE_THROWS_AS(SuccessCriterion::read(yaml("{term: distance}"), wrong, kinds), Error);
    REQUIRE_THROWS_WITH(SuccessCriterion::read(yaml("{term: distance}"), wrong, kinds),
                        Catch::Equals("success term distance: d0 defaults to the reward term's value; expected a "
                                      "number, found \"far\""));
  }
  SECTION("a hold carries across actions and breaks when the condition fails") {
    const SuccessCriterion c = SuccessCriterion::read(yaml("{term: distance, within: 0.1, hold_s: 0.2}"), keep, kinds);
    SuccessCriterion::Tracker tracker(c, m.frameTime);
    CHECK(tracker.play(m, 1, {0, 0, 1.05}) == 0);  // 4 of 6 frames
    CHECK(tracker.play(m, 1, {0, 0, 1.05}) == 2);
    SuccessCriterion::Tracker broken(c, m.frameTime);
    CHECK(broken.play(m, 1, {0, 0, 1.05}) == 0);
    CHECK(broken.play(m, 1, {0, 0, 3}) == 0);  // out of range: the count starts over
    CHECK(broken.play(m, 1, {0, 0, 1.05}) == 0);
  }
  SECTION("all conditions at once") {
    const SuccessCriterion c = SuccessCriterion::read(
        yaml("{all: [{term: distance, within: 0.1}, {term: facing, within_deg: 10}], hold_s: 0}"), keep, kinds);
    SuccessCriterion::Tracker ahead(c, m.frameTime), side(c, m.frameTime);
    CHECK(ahead.play(m, 1, {0, 0, 1}) == 1);
    CHECK(side.play(m, 1, {1, 0, 0}) == 0);  // 1 m away but 90 degrees off
  }
  SECTION("contact: the hit preset implies it, kicks count with feet") {
    const auto implied = SuccessCriterion::implied(
        app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.1}"))->terms(), kinds);
    REQUIRE(implied);
    SuccessCriterion::Tracker punch(*implied, m.frameTime);
    CHECK(punch.play(m, 0, {0, 1.3, 0.6}) == 2);
    CHECK_FALSE(SuccessCriterion::implied(app::plugins().rewards.create(yaml("{type: approach}"))->terms(), kinds));
    const SuccessCriterion kick =
        SuccessCriterion::read(yaml("{term: contact, effector: feet, radius: 0.1}"), keep, kinds);
    SuccessCriterion::Tracker foot(kick, m.frameTime);
    CHECK(foot.play(m, 0, {0.2, 0.9, 0.7}) == 3);
  }
  SECTION("a new success term is a registration: its keys default to the reward term's, hold_s applies") {
    // A condition kind registered here, not in success.cpp: the pelvis's ground distance
    // to the target at least `beyond` m, `beyond` inherited from a reward term of its name.
    class Far final : public SuccessCondition {
     public:
      explicit Far(const Params& p) : beyond_(p.number("beyond")) {}
      bool holds(const ConditionFrame& f) const override {
        return bodyDistance(f.model, f.frame, BodyPoint::pelvis(), 2, f.target.position) >= beyond_;
      }
      nlohmann::json toJson() const override { return {{"term", "far"}, {"beyond", beyond_}}; }
      std::string describe() const override { return fmt::format("at least {:g} m away", beyond_); }

     private:
      double beyond_;
    };
    ConditionRegistry mine("success term");
    ConditionRegistry::Entry far{
        "far", "at least beyond m away", {ParamSpec::number("beyond", 1, 0, 10, "m", "")}, [](const Params& p) {
          return std::make_unique<Far>(p);
        }};
    far.inherited = {"beyond"};
    mine.add(std::move(far));
    const nlohmann::json withFar = nlohmann::json::array({{{"term", "far"}, {"beyond", 2.0}}});
    const SuccessCriterion inherited = SuccessCriterion::read(yaml("{term: far, hold_s: 0.1}"), withFar, mine);
    CHECK(inherited.describe() == "at least 2 m away for 0.1 s");
    SuccessCriterion::Tracker beyond(inherited, m.frameTime), within(inherited, m.frameTime);
    CHECK(beyond.play(m, 1, {0, 0, 2.5}) == 3);
    CHECK(within.play(m, 1, {0, 0, 1.5}) == 0);
    CHECK(SuccessCriterion::read(yaml("{term: far}"), keep, mine).describe() == "at least 1 m away");
    CHECK(SuccessCriterion::read(yaml("{term: far, beyond: 3}"), withFar, mine).describe() == "at least 3 m away");
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: distance}"), keep, mine),
                      Catch::Contains("unknown success term 'distance' (known: far)"));
  }
  SECTION("mistakes name the line, column and key") {
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: contact, hold_s: 1}"), keep, kinds),
                      Catch::Contains("hold_s: expected no hold_s with a contact condition"));
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: distance, within: -1}"), keep, kinds),
                      Catch::StartsWith("test.yaml:1:26: within: "));
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: speed}"), keep, kinds),
                      Catch::Contains("term: ") && Catch::Contains("speed"));
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: distance, sigma: 1}"), keep, kinds),
                      Catch::Contains("sigma: unknown key"));
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("[distance]"), keep, kinds), Catch::Contains("expected a map"));
  }
}


TEST_CASE("a sampled Bellman residual measures one pair in k, below the whole table's, and leaves the table alone",
          "[learning]") {
  const CorridorSetup parts(2);
  const Problem& problem = parts.problem;
  const GridModel& g = parts.tabulated;
  // A table part of the way: residuals well above zero.
  const TrainResult q = trainWith("{type: q_learning, budget: 300, seed: 3, curve_points: 1}", problem, g);
  const Residual whole = bellmanResidual(q.table, g, 2);
  REQUIRE(whole.max > 0.01);
  // Stride 1 is the whole table; the sample's max is a lower bound, its mean nearby.
  const Residual one = bellmanResidual(q.table, g, 1, 1);
  CHECK(one.max == whole.max);
  CHECK(one.mean == Approx(whole.mean).epsilon(1e-12));
  for (std::size_t k : {2, 3, 8, 1000}) {
    CAPTURE(k);
    const Residual sampled = bellmanResidual(q.table, g, 2, k);
    CHECK(sampled.max <= whole.max);
    if (k <= 8) CHECK(sampled.max > 0);  // 1000: a vertex per action, maybe all settled
    // Deterministic whatever the thread count.
    const Residual single = bellmanResidual(q.table, g, 1, k);
    CHECK(single.max == sampled.max);
    CHECK(single.mean == Approx(sampled.mean).epsilon(1e-12));
  }
  // q_learning's curve_sample changes the curve only: the same table, and an exact final residual.
  const TrainResult exact = trainWith("{type: q_learning, budget: 3000, seed: 3, curve_points: 3, curve_sample: 1}", problem, g);
  const TrainResult sampled = trainWith("{type: q_learning, budget: 3000, seed: 3, curve_points: 3, curve_sample: 4}", problem, g);
  CHECK(std::equal(exact.table.values().begin(), exact.table.values().end(), sampled.table.values().begin()));
  CHECK(sampled.finalResidual == exact.finalResidual);
  REQUIRE(sampled.curve.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) CHECK(sampled.curve[i].residual <= exact.curve[i].residual);
}


TEST_CASE("a compact model trains the same tables as the tabulated one in a fifth of the memory", "[learning][compact]") {
  // Rewards only, each backup finding where its vertex lands; q_learning (whose
  // walk finds the landings of its steps' corners) and value iteration, 2-D and 3-D grids.
  SyntheticModelSpec spec;
  spec.states = 40;
  spec.actions = 1500;
  const StateActionModel m = makeSyntheticModel(spec);
  const auto polar = makeGrid("{type: polar2d, radius: 2, rings: 5, sectors: 13}", m);
  const auto cylinder = makeGrid("{type: cylindrical3d, bounds: hits, angles: 6, distances: 5, heights: 3}", m);
  const auto hit = app::plugins().rewards.create(yaml("{type: hit, contact_radius: 0.15}"));
  const auto approach = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.1}"));
  const StaticTarget environment;
  for (const auto& [grid, reward] : {std::pair{polar.get(), approach.get()}, std::pair{cylinder.get(), hit.get()}}) {
    CAPTURE(grid->type());
    const Problem problem{m, *grid, *reward, environment};
    const GridModel tabulated = GridModel::build(problem, 2);
    const GridModel compact = GridModel::buildCompact(problem, 2);
    REQUIRE(compact.compact());
    REQUIRE_FALSE(tabulated.compact());
    CHECK(compact.transition.empty());
    // Every record the same bytes, found now instead of stored.
    for (std::size_t a = 0; a < m.actionCount(); a += 7)
      for (std::size_t v = 0; v < grid->vertexCount(); ++v) {
        const GridTransition x = tabulated.transition[a * tabulated.vertexCount + v], y = compact.at(a, v);
        REQUIRE(std::memcmp(&x, &y, sizeof x) == 0);
      }
    const double qBytes = static_cast<double>(m.actionCount() * grid->vertexCount() * sizeof(float));
    CHECK(static_cast<double>(compact.bytes()) < 1.3 * qBytes);
    CHECK(static_cast<double>(tabulated.bytes()) > 4.5 * qBytes);
    // With value iteration's two tables and its staging buffer: 16 bytes a pair against 32.
    CHECK(GridModel::trainingBytes(m.actionCount(), grid->vertexCount(), true) <
          0.55 * GridModel::trainingBytes(m.actionCount(), grid->vertexCount(), false));
    for (const char* learner : {"{type: q_learning, budget: 300000, seed: 4, curve_points: 3, checkpoint_every: 0}",
                                "{type: value_iteration, tolerance: 1e-4}"}) {
      CAPTURE(learner);
      const TrainResult a = trainWith(learner, problem, tabulated), b = trainWith(learner, problem, compact);
      REQUIRE(a.table.values().size() == b.table.values().size());
      CHECK(std::memcmp(a.table.values().data(), b.table.values().data(), a.table.values().size() * sizeof(float)) == 0);
      CHECK(a.finalResidual == b.finalResidual);
      CHECK(a.updates == b.updates);
    }
  }
}

}  // namespace mgrl::learning_test

// ---- Moving targets: moving_target, polar_velocity's speed layers ----

namespace mgrl::learning_test {
namespace {

// One state; the action walks 0.5 m forward over 15 frames (0.5 s) turning 0.3 rad left.
StateActionModel turningWalk() { return handModel(1, {{0, 0, 15, 0, 0.5, 0.3, {}}}); }

constexpr const char* kLayeredGrid =
    "{type: polar_velocity, distance_max: 2, rings: 3, sectors: 4, headings: 4, speeds: 3, max_speed: 1, "
    "height_from: given, height: 1}";

// Halves the target's speed: what a grid with speed layers must refuse to learn on.
class SlowingTarget final : public EnvironmentModel {
 public:
  std::string type() const override { return "slowing"; }
  TargetState next(const StateActionModel& m, std::size_t a, const TargetState& e) const override {
    return {inverseTransformPoint(m.displacement(a), e.position), e.speed / 2, e.heading};
  }
};

}  // namespace

TEST_CASE("moving_target: the target moves along its velocity, its heading turns with the avatar, its speed is kept",
          "[learning][moving]") {
  const StateActionModel m = turningWalk();
  const MovingTarget environment(0, 1);
  const TargetState e(Eigen::Vector3d(1.0, 1.2, 2.0), 0.8, 0.4);
  const TargetState next = environment.next(m, 0, e);
  // Half a second later the target is at p + v / 2 in the decision's frame ...
  const Eigen::Vector3d expected = e.position + 0.5 * Eigen::Vector3d(0.8 * std::sin(0.4), 0, 0.8 * std::cos(0.4));
  const Eigen::Vector3d back = transformPoint(m.displacement(0), next.position);
  CHECK(back.x() == Approx(expected.x()).margin(1e-12));
  CHECK(back.y() == Approx(1.2).margin(1e-12));
  CHECK(back.z() == Approx(expected.z()).margin(1e-12));
  // ... its velocity is the same in the world, so 0.3 rad less in the turned frame ...
  CHECK(next.heading == Approx(0.1).margin(1e-12));
  // ... and its speed is the same number, not a recomputed one (it is a grid layer).
  CHECK(next.speed == 0.8);
  // A static state moves rigidly, exactly as static_target moves it.
  const StaticTarget still;
  CHECK(environment.next(m, 0, e.position).position == still.next(m, 0, e.position).position);
  CHECK(TargetState(e.position).at(0.5) == e.position);

  SECTION("draws speeds in [min_speed, max_speed] and headings all round") {
    const MovingTarget drawn(0.25, 0.75);
    Rng rng(3);
    double lowest = 1, highest = 0, left = 0;
    for (int i = 0; i < 2000; ++i) {
      const TargetState s = drawn.draw(Eigen::Vector3d(0, 1, 1), rng);
      CHECK(s.position == Eigen::Vector3d(0, 1, 1));
      lowest = std::min(lowest, s.speed);
      highest = std::max(highest, s.speed);
      left += s.heading > 0;
      REQUIRE(std::abs(s.heading) <= M_PI);
    }
    CHECK(lowest >= 0.25);
    CHECK(lowest < 0.26);
    CHECK(highest <= 0.75);
    CHECK(highest > 0.74);
    CHECK(left / 2000 == Approx(0.5).margin(0.05));
  }

  SECTION("rewards and success look where the target is at each frame") {
    // The centroid starts 0.5 m ahead and walks 0.5 m: a target 1.5 m ahead coming at
    // 1 m/s meets it at 1 m after 0.5 s; the same target standing still is 0.5 m short.
    const auto approach = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.1, gamma: 1}"));
    const StateActionModel straight = handModel(1, {{0, 0, 15, 0, 0.5, 0, {}}});
    const TargetState coming(Eigen::Vector3d(0, 1, 1.5), 1.0, M_PI);
    CHECK(approach->evaluate(straight, 0, coming) == Approx(1.0).margin(1e-6));
    CHECK(approach->evaluate(straight, 0, coming.position) == Approx(std::exp(-0.5 / 0.1)).margin(1e-6));
    const SuccessCriterion near = SuccessCriterion::read(yaml("{term: distance, point: centroid, within: 0.05}"),
                                                         nlohmann::json::array(), app::plugins().conditions);
    SuccessCriterion::Tracker moving(near, straight.frameTime), standing(near, straight.frameTime);
    CHECK(moving.play(straight, 0, coming) > 0);
    CHECK(standing.play(straight, 0, coming.position) == 0);
  }
}

TEST_CASE("bounds: hits takes the box of the effective hitting points: an area for ground grids, a volume for 3-D",
          "[learning][discretizer]") {
  SyntheticModelSpec spec;
  spec.states = 10;
  spec.actions = 200;
  StateActionModel m = makeSyntheticModel(spec);
  REQUIRE(m.hits.size() >= 2);
  // The box is the hits' own, widened by the margins; the axes span it exactly.
  double lo = INFINITY, hi = -INFINITY;
  for (const ActionHit& h : m.hits) {
    lo = std::min(lo, std::hypot(static_cast<double>(h.x), static_cast<double>(h.z)));
    hi = std::max(hi, std::hypot(static_cast<double>(h.x), static_cast<double>(h.z)));
  }
  const auto cylinder = makeGrid("{type: cylindrical3d, bounds: hits, margin: 0.05, angles: 4, distances: 3}", m);
  const GridAxis* distance = cylinder->axis(AxisRole::Distance);
  REQUIRE(distance != nullptr);
  CHECK(distance->vertices.front() == Approx(std::max(0.0, lo - 0.05)));
  CHECK(distance->vertices.back() == Approx(hi + 0.05));
  // Every hit at one height: polar_velocity (no height axis) still has an area to take;
  // cylindrical3d has no volume and says so.
  for (ActionHit& h : m.hits) h.y = 1.4f;
  const auto ground = makeGrid("{type: polar_velocity, bounds: hits, sectors: 4, rings: 3, headings: 4}", m);
  CHECK(ground->axis(AxisRole::Distance)->vertices.back() == Approx(hi));
  REQUIRE_THROWS_WITH(makeGrid("{type: cylindrical3d, bounds: hits}", m),
                      Catch::Contains("bounds: expected the effective hitting points to span a volume, found them "
                                      "all on one plane; set bounds: given"));
  // ...and every hit at one spot leaves a ground grid no area either.
  for (ActionHit& h : m.hits) {
    h.x = 0.1f;
    h.z = 0.6f;
  }
  REQUIRE_THROWS_WITH(makeGrid("{type: polar_velocity, bounds: hits}", m),
                      Catch::Contains("bounds: expected the effective hitting points to span an area, found them "
                                      "all at one angle or one distance; set bounds: given"));
}

TEST_CASE("polar_velocity: vertices sit on speed layers, backups stay on them, decisions interpolate across two",
          "[learning][moving]") {
  const StateActionModel m = turningWalk();
  const auto grid = makeGrid(kLayeredGrid, m);
  REQUIRE(grid->dimension() == 3);
  REQUIRE(grid->layerAxis() != nullptr);
  CHECK(grid->layerAxis()->vertices == std::vector<double>{0, 0.5, 1});
  CHECK(grid->layerVertexCount() == 4 * 3 * 4);
  CHECK(grid->vertexCount() == 4 * 3 * 4 * 3);
  CHECK(grid->describe()["layers"]["name"] == "speed");
  // Too many vertices in all is refused before the layered corner table is made.
  REQUIRE_THROWS_WITH(
      makeGrid("{type: polar_velocity, sectors: 100, rings: 100, headings: 100, speeds: 100}", m),
      Catch::Contains("expected a grid of at most 20000000 vertices, found 100000000 (1000000 per layer x 100 speed)"));

  // Every vertex, the top layer's included, locates on its own layer with weight 1 on itself.
  for (std::size_t v = 0; v < grid->vertexCount(); ++v) {
    const TargetState e = grid->vertexState(v);
    CHECK(e.speed == grid->layerAxis()->vertices[v / grid->layerVertexCount()]);
    CHECK(e.position.y() == 1.0);
    GridCell cell;
    REQUIRE(grid->locate(e, cell));
    CHECK(cell.layerFrac == 0);
    const Stencil s = grid->stencil(cell);
    REQUIRE(s.size == 8);
    // (At distance 0 the angle is lost: the weight goes to the angle-0 vertex of the same point.)
    if (e.position.x() == 0 && e.position.z() == 0) continue;
    double own = 0;
    for (int k = 0; k < s.size; ++k)
      if (s.vertex[k] == v) own += s.weight[k];
    CHECK(own == Approx(1).margin(1e-6));
  }

  // Between layers: 16 corners, the upper 8 weighted by the fraction, and a function linear
  // in (distance, speed) reproduced.
  const TargetState between(Eigen::Vector3d(0.3, 1, 0.9), 0.35, 0.2);
  GridCell cell;
  REQUIRE(grid->locate(between, cell));
  CHECK(cell.layerFrac == Approx(0.7));
  const Stencil s = grid->stencil(cell);
  REQUIRE(s.size == 16);
  double sum = 0, upper = 0, value = 0;
  for (int k = 0; k < s.size; ++k) {
    sum += s.weight[k];
    if (k >= 8) upper += s.weight[k];
    const TargetState corner = grid->vertexState(s.vertex[k]);
    value += s.weight[k] * (2 * std::hypot(corner.position.x(), corner.position.z()) - 3 * corner.speed);
  }
  CHECK(sum == Approx(1).margin(1e-6));
  CHECK(upper == Approx(0.7).margin(1e-6));
  CHECK(value == Approx(2 * std::hypot(0.3, 0.9) - 3 * 0.35).margin(1e-5));
  // Faster than the top layer: outside (a hit grid is inactive), clamped to the top layer.
  GridCell ignored;
  CHECK_FALSE(grid->locate(TargetState(between.position, 1.5, 0), ignored));
  CHECK(grid->locateClamped(TargetState(between.position, 1.5, 0)).layerFrac == 0);
  // Restarts draw a fourth number for the layer, and land exactly on one.
  for (double u : {0.0, 0.4, 0.9999}) {
    const TargetState drawn = grid->sample({0.5, 0.5, 0.5, u});
    CHECK(drawn.speed == grid->layerAxis()->vertices[static_cast<std::size_t>(u * 3)]);
  }

  SECTION("learning on it: a moving_target keeps every backup on its layer; a model that slows the target is refused") {
    const auto reward = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.3}"));
    const MovingTarget moving(0, 1);
    const Problem problem{m, *grid, *reward, moving};
    const GridModel g = GridModel::build(problem, 2);
    CHECK(g.dimension == 3);
    // Landings stay in the source vertex's layer: the cell's layer is v's.
    const std::size_t cellsPerLayer = grid->cellCount() / 3;
    for (std::size_t v = 0; v < g.vertexCount; ++v) {
      const GridTransition& t = g.transition[v];
      if (t.cell >= 0) CHECK(static_cast<std::size_t>(t.cell) / cellsPerLayer == v / grid->layerVertexCount());
    }
    const GridModel compact = GridModel::buildCompact(problem, 2);
    for (std::size_t v = 0; v < g.vertexCount; ++v) {
      const GridTransition a = g.at(0, v), b = compact.at(0, v);
      CHECK(a.cell == b.cell);
      CHECK(a.reward == b.reward);
    }
    const SlowingTarget slowing;
    const Problem refused{m, *grid, *reward, slowing};
    REQUIRE_THROWS_WITH(GridModel::build(refused, 1), Catch::Contains("landed between speed layers") &&
                                                          Catch::Contains("must keep the target's speed"));
  }
}

TEST_CASE("Q-learning on speed layers: restarts on a layer, checkpoints keep the target's motion, a resumed run "
          "ends with the uninterrupted table",
          "[learning][moving][checkpoint]") {
  // Two states, walks forward and back with turns: targets move between cells and layers stay.
  const StateActionModel m = handModel(2, {{0, 1, 15, 0.1, 0.5, 0.3, {}},
                                           {1, 0, 12, -0.1, 0.3, -0.4, {}},
                                           {0, 0, 10, 0, -0.3, 0.2, {}},
                                           {1, 1, 20, 0.2, 0.6, 0, {}}});
  const auto grid = makeGrid(kLayeredGrid, m);
  const auto reward = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.3}"));
  const MovingTarget moving(0, 1);
  const Problem problem{m, *grid, *reward, moving};
  const GridModel g = GridModel::build(problem, 2);
  const std::string learner = "{type: q_learning, budget: 3000, seed: 4, checkpoint_every: 1000, curve_points: 3}";
  const TrainResult whole = trainWith(learner, problem, g);
  REQUIRE(trainWith(learner, problem, g).table == whole.table);

  MemoryCheckpointer store(2);
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &store), "simulated crash");
  // The walk's target is saved with its speed and heading; its speed is a layer's.
  const nlohmann::json& walk = store.state()["walk"];
  REQUIRE(walk.contains("target_motion"));
  const double speed = walk["target_motion"][0].get<double>();
  CHECK((speed == 0 || speed == 0.5 || speed == 1));
  MemoryCheckpointer resumed = store;
  const TrainResult finished = trainWith(learner, problem, g, &resumed);
  REQUIRE(finished.stats["resumed"] == true);
  REQUIRE(finished.table == whole.table);

  // A damaged motion is refused with the member's path, what was expected and what was found.
  MemoryCheckpointer damaged = store;
  damaged.state()["walk"]["target_motion"] = nlohmann::json::array({-1, 0});
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &damaged),
                      Catch::Contains("state.walk.target_motion: expected 2 or 3 finite numbers: a speed >= 0 (m/s), "
                                      "a heading (rad) and a turn rate (rad/s), found '[-1,0]'"));
}

// ---- Turning targets: moving_target's turn rates, a grid's turn layers ----

TEST_CASE("a turning target runs round its circle, next() keeps its turn rate and replays exactly over actions",
          "[learning][moving][turning]") {
  // Heading 0 (towards +Z) turning a quarter circle a second towards +X at 1 m/s: the
  // circle's radius is 2 / pi, so after 1 s the target is r to the left and r ahead.
  TargetState e(Eigen::Vector3d(0.5, 1.2, 1.0), 1.0, 0.0);
  e.turnRate = M_PI / 2;
  const double r = 2 / M_PI;
  CHECK((e.at(1.0) - Eigen::Vector3d(0.5 + r, 1.2, 1.0 + r)).norm() < 1e-12);
  CHECK(e.headingAt(1.0) == Approx(M_PI / 2));
  CHECK((e.at(4.0) - e.position).norm() < 1e-12);  // a whole turn comes back
  // at() is the integral of the turning velocity (midpoint rule, 10^4 steps over 0.7 s).
  Eigen::Vector3d walked = e.position;
  for (int k = 0; k < 10000; ++k) {
    const double t = (k + 0.5) * 0.7 / 10000, h = e.heading + e.turnRate * t;
    walked += 0.7 / 10000 * Eigen::Vector3d(std::sin(h), 0, std::cos(h));
  }
  CHECK((e.at(0.7) - walked).norm() < 1e-8);
  // Turn rate 0 is the straight line, bit for bit.
  const TargetState straight(e.position, 1.0, 0.3);
  CHECK(straight.at(0.7) == Eigen::Vector3d(e.position + 0.7 * straight.velocity()));
  CHECK(straight.headingAt(0.7) == 0.3);

  // next(): seen back from the world the target is where at() says, its heading has turned
  // by w T and back by the avatar's yaw, and its turn rate is the same number.
  const StateActionModel m = turningWalk();
  const MovingTarget turning(0, 1, {-M_PI / 2, 0, M_PI / 2});
  const TargetState one = turning.next(m, 0, e);
  CHECK((transformPoint(m.displacement(0), one.position) - e.at(0.5)).norm() < 1e-12);
  CHECK(one.heading == Approx(M_PI / 4 - 0.3));
  CHECK(one.turnRate == e.turnRate);
  CHECK(one.speed == e.speed);
  // Three actions in a row land where the first decision's at(1.5) says: what the table
  // assumes is what a trial that replays the actions sees.
  TargetState later = e;
  GroundMotion avatar{0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    later = turning.next(m, 0, later);
    avatar = compose(avatar, m.displacement(0));
  }
  CHECK((transformPoint(avatar, later.position) - e.at(1.5)).norm() < 1e-9);
  CHECK(std::remainder(later.heading + avatar.dyaw - e.headingAt(1.5), 2 * M_PI) == Approx(0).margin(1e-9));

  SECTION("draws only its turn rates, each as often; without them its random stream is the straight line's") {
    Rng rng(5);
    std::array<int, 3> counts{0, 0, 0};
    const std::vector<double> rates = turning.as<TargetMotion>()->turnRates;
    for (int i = 0; i < 3000; ++i) {
      const double w = turning.draw(Eigen::Vector3d(0, 1, 1), rng).turnRate;
      const auto found = std::find(rates.begin(), rates.end(), w);
      REQUIRE(found != rates.end());
      ++counts[static_cast<std::size_t>(found - rates.begin())];
    }
    for (int c : counts) CHECK(c / 3000.0 == Approx(1 / 3.0).margin(0.04));
    Rng drawn(9), plain(9);
    CHECK(MovingTarget(0, 1).draw(Eigen::Vector3d(0, 1, 1), drawn).turnRate == 0);
    plain.uniform();
    plain.uniform();
    CHECK(drawn.state() == plain.state());
  }
}

TEST_CASE("turn layers: one copy of the speed-layered grid per turn rate, never interpolated across, kept by backups",
          "[learning][moving][turning]") {
  const StateActionModel m = turningWalk();
  const std::vector<double> rates{-M_PI / 2, 0, M_PI / 2};
  auto grid = makeGrid(kLayeredGrid, m);
  const std::size_t perTurn = grid->vertexCount(), cellsPerTurn = grid->cellCount();
  grid->setTurnLayers(rates);
  CHECK(grid->turnVertexCount() == perTurn);
  CHECK(grid->vertexCount() == 3 * perTurn);
  CHECK(grid->cellCount() == 3 * cellsPerTurn);
  CHECK(grid->cellCorners().size() == grid->cellCount() << 3);
  CHECK(grid->axis(AxisRole::Turn) == grid->turnAxis());
  CHECK(grid->describe()["turn_layers"]["name"] == "turn");
  CHECK(grid->describe()["turn_layers"]["unit"] == "rad/s");

  // Every vertex is on its speed and turn layer, and locates onto itself in that layer.
  for (std::size_t v = 0; v < grid->vertexCount(); ++v) {
    const TargetState e = grid->vertexState(v);
    CHECK(e.turnRate == rates[v / perTurn]);
    CHECK(e.speed == grid->layerAxis()->vertices[v % perTurn / grid->layerVertexCount()]);
    GridCell cell;
    REQUIRE(grid->locate(e, cell));
    const Stencil s = grid->stencil(cell);
    double own = 0;
    for (int k = 0; k < s.size; ++k) {
      CHECK(s.vertex[k] / perTurn == v / perTurn);
      if (s.vertex[k] == v) own += s.weight[k];
    }
    if (e.position.x() != 0 || e.position.z() != 0) CHECK(own == Approx(1).margin(1e-6));
  }
  // Between two speeds and turning at 1.2 rad/s: 16 corners across the speeds, all in the
  // nearest turn layer (pi / 2), none in another; a NaN turn rate is outside.
  TargetState between(Eigen::Vector3d(0.3, 1, 0.9), 0.35, 0.2);
  between.turnRate = 1.2;
  GridCell cell;
  REQUIRE(grid->locate(between, cell));
  const Stencil s = grid->stencil(cell);
  REQUIRE(s.size == 16);
  for (int k = 0; k < s.size; ++k) CHECK(s.vertex[k] / perTurn == 2);
  CHECK(grid->turnLayer(-0.2) == 1);
  CHECK(grid->turnLayer(-5) == 0);
  between.turnRate = NAN;
  CHECK_FALSE(grid->inside(between));
  // Restarts land on one of speeds x turn rates.
  for (double u : {0.0, 0.4, 0.9999}) {
    const TargetState drawn = grid->sample({0.5, 0.5, 0.5, u});
    const auto pick = static_cast<std::size_t>(u * 9);
    CHECK(drawn.speed == grid->layerAxis()->vertices[pick % 3]);
    CHECK(drawn.turnRate == rates[pick / 3]);
  }

  // Refusals, each in one line.
  REQUIRE_THROWS_WITH(grid->setTurnLayers({0, 1}), Catch::Contains("the grid has turn layers already"));
  REQUIRE_THROWS_WITH(makeGrid(kLayeredGrid, m)->setTurnLayers({1, 0}),
                      Catch::Contains("expected finite ascending turn rates, found 0 at 1"));
  REQUIRE_THROWS_WITH(makeGrid("{type: kd_tree, bounds: given}", m)->setTurnLayers(rates),
                      Catch::Contains("kd_tree: an adaptive grid cannot hold turn layers; use polar_velocity"));
  REQUIRE_THROWS_WITH(makeGrid("{type: kd_tree, bounds: given}", m)->setOpponentLayers(4),
                      Catch::Contains("kd_tree: an adaptive grid cannot hold opponent layers; use polar_velocity"));
  REQUIRE_THROWS_WITH(makeGrid(kLayeredGrid, m)->setTurnLayers({}),
                      Catch::Contains("expected at least 1 turn rate, found none"));
  auto turning = makeGrid("{type: polar_velocity, distance_max: 2, rings: 3, sectors: 4, headings: 4, speeds: 1}", m);
  turning->setTurnLayers(rates);
  REQUIRE_THROWS_WITH(turning->setOpponentLayers(4),
                      Catch::Contains("opponent layers cannot be added after turn layers"));
  auto fighting = makeGrid("{type: polar_velocity, distance_max: 2, rings: 3, sectors: 4, headings: 4, speeds: 1}", m);
  fighting->setOpponentLayers(4);
  REQUIRE_THROWS_WITH(fighting->setTurnLayers(rates), Catch::Contains("a learned opponent's layers cannot turn"));
  auto big = makeGrid("{type: polar_velocity, sectors: 100, rings: 100, headings: 100, speeds: 1}", m);
  REQUIRE_THROWS_WITH(
      big->setTurnLayers(std::vector<double>{-3, -2, -1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17}),
      Catch::Contains("expected a grid of at most 20000000 vertices, found 21000000 (1000000 per "
                      "turn layer x 21 turn rates)"));

  SECTION("learning on it: every backup stays in its vertex's turn and speed layer; compact agrees") {
    const auto reward = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.3}"));
    const MovingTarget moving(0, 1, rates);
    const Problem problem{m, *grid, *reward, moving};
    const GridModel g = GridModel::build(problem, 2);
    const std::size_t cellsPerSpeed = grid->cellCount() / 9;
    std::size_t landed = 0;
    for (std::size_t v = 0; v < g.vertexCount; ++v) {
      const GridTransition& t = g.transition[v];
      if (t.cell < 0) continue;
      ++landed;
      CHECK(static_cast<std::size_t>(t.cell) / cellsPerSpeed == v / grid->layerVertexCount());
    }
    CHECK(landed > g.vertexCount / 4);
    const GridModel compact = GridModel::buildCompact(problem, 2);
    for (std::size_t v = 0; v < g.vertexCount; ++v) {
      const GridTransition a = g.at(0, v), b = compact.at(0, v);
      CHECK(a.cell == b.cell);
      CHECK(a.reward == b.reward);
    }
  }
}

TEST_CASE(
    "Q-learning on turn layers: checkpoints keep the target's turn rate, a resumed run ends with the "
    "uninterrupted table",
    "[learning][moving][turning][checkpoint]") {
  const StateActionModel m = handModel(2, {{0, 1, 15, 0.1, 0.5, 0.3, {}},
                                           {1, 0, 12, -0.1, 0.3, -0.4, {}},
                                           {0, 0, 10, 0, -0.3, 0.2, {}},
                                           {1, 1, 20, 0.2, 0.6, 0, {}}});
  auto grid = makeGrid(kLayeredGrid, m);
  grid->setTurnLayers({-1, 1});  // no straight line: every walk's target turns
  const auto reward = app::plugins().rewards.create(yaml("{type: approach, sigma: 0.3}"));
  const MovingTarget moving(0, 1, {-1, 1});
  const Problem problem{m, *grid, *reward, moving};
  const GridModel g = GridModel::build(problem, 2);
  const std::string learner = "{type: q_learning, budget: 3000, seed: 4, checkpoint_every: 1000, curve_points: 3}";
  const TrainResult whole = trainWith(learner, problem, g);
  MemoryCheckpointer store(2);
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &store), "simulated crash");
  const nlohmann::json& walk = store.state()["walk"];
  REQUIRE(walk["target_motion"].size() == 3);
  const double w = walk["target_motion"][2].get<double>();
  CHECK((w == -1 || w == 1));
  MemoryCheckpointer resumed = store;
  const TrainResult finished = trainWith(learner, problem, g, &resumed);
  REQUIRE(finished.stats["resumed"] == true);
  REQUIRE(finished.table == whole.table);
  MemoryCheckpointer damaged = store;
  damaged.state()["walk"]["target_motion"] = nlohmann::json::array({0.5, 0, 1, 2});
  REQUIRE_THROWS_WITH(trainWith(learner, problem, g, &damaged),
                      Catch::Contains("state.walk.target_motion: expected 2 or 3 finite numbers: a speed >= 0 (m/s), "
                                      "a heading (rad) and a turn rate (rad/s), found '[0.5,0,1,2]'"));
}

TEST_CASE("compare --reference-set refuses a grid with speed layers in one line", "[learning][moving]") {
  const StateActionModel m = turningWalk();
  const auto layered = makeGrid(kLayeredGrid, m);
  const auto polar = makeGrid("{type: polar2d, radius: 3, rings: 7, sectors: 13}", m);
  REQUIRE_THROWS_WITH(requireCovers(*polar, *layered, "approach"),
                      "--reference-set: behaviors.approach: a polar_velocity grid has speed layers, which a reference "
                      "set cannot be compared on yet; compare without --reference-set (against value iteration on "
                      "the same grid)");
  REQUIRE_THROWS_WITH(requireCovers(*layered, *polar, "approach"), Catch::Contains("a polar_velocity grid"));
}

namespace {

// kickingModel() with one joint, the head, 1.3 m up and 0.1 m ahead of the pelvis in every
// frame. Its one punch lands at (0, 1.3, 0.4) in the puncher's own frame (0.6 m ahead at
// offset 2 of action 0, which has walked 0.2 m by then).
StateActionModel headModel() {
  StateActionModel m = kickingModel();
  m.jointNames = {"Head"};
  m.roleJoint.assign(roleNames().size(), 0);
  m.framesTotal = 1;
  m.sourceJoint = {0.0f, 1.3f, 0.1f};
  m.sourceJointSpeed = {0.0f};
  return m;
}

}  // namespace

TEST_CASE("opponent: walks toward the avatar until stop_distance, turns to face it at turn_rate, seen from the "
          "action's end",
          "[learning][opponent]") {
  const StateActionModel m = turningWalk();  // 0.5 s: 0.5 m ahead, turning 0.3 rad
  const GroundMotion d = m.displacement(0);
  const auto inDecisionFrame = [&](const TargetState& next) {
    return std::pair(transformPoint(d, next.position), std::remainder(next.heading + d.dyaw, 2 * M_PI));
  };
  SECTION("pursue: 0.4 m/s for 0.5 s is 0.2 m toward where the avatar ends") {
    const environments::Opponent pursue(true, 0.4, 0.7, M_PI);
    const TargetState next = pursue.next(m, 0, TargetState(Eigen::Vector3d(0, 1.1, 3), 0, M_PI));
    const auto [p, facing] = inDecisionFrame(next);
    CHECK(p.x() == Approx(0).margin(1e-12));
    CHECK(p.y() == Approx(1.1).margin(1e-12));
    CHECK(p.z() == Approx(2.8).margin(1e-12));
    CHECK(std::abs(facing) == Approx(M_PI).margin(1e-12));
    CHECK(next.speed == 0);
  }
  SECTION("pursue stops stop_distance from the avatar, never walks into it") {
    const environments::Opponent pursue(true, 0.4, 0.7, M_PI);
    const auto [p, facing] = inDecisionFrame(pursue.next(m, 0, TargetState(Eigen::Vector3d(0, 1, 1.3), 0, M_PI)));
    CHECK(p.z() == Approx(1.2).margin(1e-12));  // 0.7 m from the avatar's end at 0.5 m
    const auto [q, facing2] = inDecisionFrame(pursue.next(m, 0, TargetState(Eigen::Vector3d(0, 1, 1.0), 0, M_PI)));
    CHECK(q.z() == Approx(1.0).margin(1e-12));  // already closer: it stays put
  }
  SECTION("turns by at most turn_rate x duration; stand does not walk") {
    const environments::Opponent stand(false, 0.4, 0.7, M_PI / 3);  // 60 deg/s: 30 deg in 0.5 s
    // 2 m to the avatar's left, facing +Z: the avatar's end is 90 degrees to its right.
    const auto [p, facing] = inDecisionFrame(stand.next(m, 0, TargetState(Eigen::Vector3d(2, 1, 0.5), 0, 0)));
    CHECK(p.x() == Approx(2).margin(1e-12));
    CHECK(p.z() == Approx(0.5).margin(1e-12));
    CHECK(facing == Approx(-M_PI / 6).margin(1e-12));
    // A fast turner faces the avatar's end exactly.
    const environments::Opponent quick(false, 0.4, 0.7, 10 * M_PI);
    CHECK(inDecisionFrame(quick.next(m, 0, TargetState(Eigen::Vector3d(2, 1, 0.5), 0, 0))).second ==
          Approx(-M_PI / 2).margin(1e-12));
  }
  SECTION("a trial's opponent starts facing the avatar; speed 0 stays on a polar_velocity layer") {
    const environments::Opponent pursue(true, 0.3, 0.7, M_PI);
    Rng rng(1);
    const TargetState start = pursue.draw(Eigen::Vector3d(1, 1.2, -1), rng);
    const Eigen::Vector3d avatar = inOpponentFrame(start, Eigen::Vector3d(0, 1.2, 0));
    CHECK(avatar.x() == Approx(0).margin(1e-12));
    CHECK(avatar.z() == Approx(std::sqrt(2.0)).margin(1e-12));  // straight ahead of it
    CHECK(pursue.next(m, 0, start).speed == start.speed);
    const auto grid = makeGrid("{type: polar_velocity, distance_max: 3, rings: 4, sectors: 6, headings: 8, speeds: 1}", m);
    GridCell cell;
    REQUIRE(grid->locate(pursue.next(m, 0, start), cell));
    CHECK(cell.layerFrac == 0);
  }
}

TEST_CASE("the opponent's reach: the graph's own strike tips in the striker's frame, as a distance field",
          "[learning][opponent]") {
  const StateActionModel m = kickingModel();
  const StrikeReach fists(m, kFists, 0.5);
  REQUIRE(fists.tips().size() == 1);
  CHECK(fists.tips()[0].isApprox(Eigen::Vector3f(0, 1.3f, 0.4f)));
  const StrikeReach feet(m, kFeet, 0.5);
  REQUIRE(feet.tips().size() == 1);
  CHECK(feet.tips()[0].isApprox(Eigen::Vector3f(0.2f, 0.9f, 0.4f)));  // the kick, at offset 3 (0.3 m walked)
  CHECK(StrikeReach(m, kAnyLimb, 0.5).tips().size() == 2);
  // The field is the exact distance up to half a 4 cm cell's diagonal, capped.
  Rng rng(5);
  double worst = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p(rng.uniform() * 1.6 - 0.8, 0.5 + rng.uniform() * 1.6, rng.uniform() * 1.6 - 0.4);
    const double exact = std::min(0.5, (p - Eigen::Vector3d(0, 1.3, 0.4)).norm());
    worst = std::max(worst, std::abs(fists.distance(p) - exact));
  }
  CHECK(worst < 0.035);
  CHECK(fists.distance({0, 1.3, 0.4}) < 0.035);
  CHECK(fists.distance({5, 0, 5}) == 0.5);
  CHECK_THROWS_WITH(StrikeReach(m, kLeftFist, 0.5), Catch::Contains("no effective strike of these limbs"));
  CHECK_THROWS_WITH(StrikeReach(m, kFists, 0), Catch::Contains("expected a cap in (0, 1] m, found 0"));
}

TEST_CASE("avoid: 0 with the head on the opponent's strike, 1 from `clear` away, success counts it held",
          "[learning][opponent]") {
  const StateActionModel m = headModel();
  const std::string block = "{type: terms, gamma: 0.9, terms: [{term: avoid, point: head, clear: 0.3, body_radius: 0}]}";
  const auto avoid = app::plugins().rewards.create(yaml(block));
  const nlohmann::json reward = avoid->terms();
  // Not evaluated before bind(): the strikes and the head come from the bound model.
  CHECK_THROWS_AS(avoid->evaluate(m, 1, Eigen::Vector3d(0, 0, 0.5)), std::logic_error);
  avoid->bind(m);
  // Action 1 stands: the head at (0, 1.3, 0.1). An opponent 0.5 m ahead facing the avatar
  // punches at 0.4 m in front of itself: on the head.
  const TargetState onHead(Eigen::Vector3d(0, 1, 0.5), 0, M_PI);
  CHECK(avoid->evaluate(m, 1, onHead) < 0.9 * 0.035 / 0.3 + 1e-9);
  // 0.8 m ahead, the strike falls 0.3 m short: the full signal.
  CHECK(avoid->evaluate(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.8), 0, M_PI)) == Approx(0.9).margin(0.9 * 0.035 / 0.3));
  // 0.65 m ahead: half.
  CHECK(avoid->evaluate(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.65), 0, M_PI)) == Approx(0.45).margin(0.11));
  // At 0.5 m but turned away: its punches go the other way.
  CHECK(avoid->evaluate(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.5), 0, 0)) == Approx(0.9).margin(1e-9));
  // Bodies of 0.2 m radius 0.5 m apart leave a 0.1 m gap: a third of the signal, however
  // the opponent faces; 0.3 m apart they overlap: none.
  const auto bodies = app::plugins().rewards.create(
      yaml("{type: terms, gamma: 0.9, terms: [{term: avoid, clear: 0.3, body_radius: 0.2}]}"));
  bodies->bind(m);
  CHECK(bodies->evaluate(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.5), 0, 0)) == Approx(0.3).margin(1e-9));
  CHECK(bodies->evaluate(m, 1, TargetState(Eigen::Vector3d(0.3, 1, 0), 0, 0)) == 0);

  SECTION("success: the head clear of its strikes for hold_s, point and effector from the reward") {
    const SuccessCriterion c =
        SuccessCriterion::read(yaml("{term: avoid, clear: 0.1, hold_s: 0.1}"), reward, app::plugins().conditions);
    REQUIRE(c.size() == 1);
    CHECK(c.toJson()["all"][0]["point"] == "head");
    CHECK(c.toJson()["all"][0]["body_radius"] == 0.0);
    CHECK(c.describe() == "the head at least 0.1 m from the opponent's strikes and body for 0.1 s");
    SuccessCriterion bound = c;
    CHECK_THROWS_AS(bound.holdsAt(m, 1, 1, onHead), std::logic_error);
    bound.bind(m);
    SuccessCriterion::Tracker safe(bound, m.frameTime), hit(bound, m.frameTime);
    CHECK(safe.play(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.5), 0, 0)) == 3);
    CHECK(hit.play(m, 1, onHead) == 0);
    // Given bodies: 0.5 m apart leaves 0.1 m, 0.45 m leaves 0.05 m.
    SuccessCriterion wide =
        SuccessCriterion::read(yaml("{term: avoid, clear: 0.08, body_radius: 0.2}"), reward, app::plugins().conditions);
    wide.bind(m);
    SuccessCriterion::Tracker apart(wide, m.frameTime), touching(wide, m.frameTime);
    CHECK(apart.play(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.5), 0, 0)) == 1);
    CHECK(touching.play(m, 1, TargetState(Eigen::Vector3d(0, 1, 0.45), 0, 0)) == 0);
  }
  SECTION("mistakes name the line, column and key") {
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: avoid, point: pelvis}"), reward, app::plugins().conditions),
                      Catch::StartsWith("test.yaml:1:22: point: ") && Catch::Contains("expected a role"));
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: avoid, clear: 2}"), reward, app::plugins().conditions),
                      Catch::StartsWith("test.yaml:1:22: clear: "));
    CHECK_THROWS_WITH(SuccessCriterion::read(yaml("{term: avoid, radius: 2}"), reward, app::plugins().conditions),
                      Catch::Contains("radius: unknown key"));
    SuccessCriterion left =
        SuccessCriterion::read(yaml("{term: avoid, effector: left_fist}"), reward, app::plugins().conditions);
    CHECK_THROWS_WITH(left.bind(m), Catch::StartsWith("test.yaml:1:25: effector: ") &&
                                        Catch::Contains("no effective strike of these limbs"));
    const auto build = [](const std::string& text) { return app::plugins().rewards.create(yaml(text)); };
    CHECK_THROWS_WITH(build("{type: terms, terms: [{term: avoid, point: centroid}]}"),
                      Catch::StartsWith("test.yaml:1:44: terms[0].point: ") && Catch::Contains("found centroid"));
    CHECK_THROWS_WITH(build("{type: terms, terms: [{term: avoid, clear: 0}]}"),
                      Catch::StartsWith("test.yaml:1:44: terms[0].clear: "));
    const auto kicks = build("{type: terms, terms: [{term: avoid, effector: left_foot}]}");
    CHECK_THROWS_WITH(kicks->bind(m), Catch::Contains("terms[0].effector: ") &&
                                          Catch::Contains("no effective strike of these limbs"));
    const auto nose = build("{type: terms, terms: [{term: avoid, point: nose}]}");
    CHECK_THROWS_WITH(nose->bind(m), Catch::Contains("terms[0].point: ") && Catch::Contains("Head"));
  }
}

TEST_CASE("trials against an avatar need an opponent environment and an avoid condition", "[learning][opponent]") {
  const StateActionModel m = headModel();
  const auto behaviours = [&](std::unique_ptr<EnvironmentModel> environment) {
    std::vector<Behavior> list(1);
    list[0].discretizer = makeGrid(
        "{type: polar_velocity, distance_max: 2, rings: 3, sectors: 4, headings: 4, speeds: 1, height_from: given, "
        "height: 1}",
        m);
    list[0].reward = app::plugins().rewards.create(yaml("{type: approach}"));
    list[0].environment = std::move(environment);
    return list;
  };
  const std::vector<Behavior> still = behaviours(std::make_unique<StaticTarget>());
  const Task stillTask = makeTask(still, "test.yaml");
  const Trials onStatic(m, still, stillTask, std::nan(""), "test.yaml", builtinPlugins().conditions);
  CHECK_FALSE(onStatic.hasAvatarOpponent());
  CHECK_THROWS_WITH(onStatic.runAgainstAvatar(nullptr, 1, 1, 1),
                    "trials against an avatar: expected an opponent environment, found static_target");
  const std::vector<Behavior> unguarded = behaviours(std::make_unique<environments::Opponent>(true, 0.3, 0.7, M_PI));
  const Task unguardedTask = makeTask(unguarded, "test.yaml");
  const Trials withoutAvoid(m, unguarded, unguardedTask, std::nan(""), "test.yaml", builtinPlugins().conditions);
  CHECK_FALSE(withoutAvoid.hasAvatarOpponent());
  CHECK_THROWS_WITH(withoutAvoid.runAgainstAvatar(nullptr, 1, 1, 1),
                    "trials against an avatar: expected a success criterion with an avoid condition, found none");
}

// Policy evaluation (self-play's best-response gap on the grid): the values of playing
// greedily on a fixed table, in the problem value iteration solves.
TEST_CASE(
    "policy evaluation: value iteration's own table is worth its values, another policy the corridor's closed "
    "form and at most those",
    "[learning][opponent]") {
  const CorridorSetup parts(2);
  const GridModel& g = parts.tabulated;
  const TrainResult vi = trainWith("{type: value_iteration, tolerance: 1e-7}", parts.problem, g);
  REQUIRE(vi.stats["converged"] == true);
  const double gamma = 0.97;
  const std::size_t forward = 0, back = 1, punch = 2, ahead = centre(*parts.grid, 0);

  // Playing value iteration's own table greedily is worth exactly its values: no gap.
  const QTable small(parts.model, 10);
  const PolicyValues own = evaluateGreedy(vi.table, g, parts.model, 2, 1e-7);
  CHECK(own.change < 1e-7);
  double largest = 0;
  for (std::size_t i = 0; i < own.q.values().size(); ++i)
    largest = std::max(largest, static_cast<double>(std::fabs(own.q.values()[i] - vi.table.values()[i])));
  CHECK(largest < 1e-4);
  CHECK(std::fabs(meanAdvantageOver(vi.table, own.q, vi.table)) < 1e-4);

  // A table that always walks back: the target recedes off the grid and nothing is ever
  // hit again, so every value is 0 but a punch at the target 0.5 m ahead, gamma^3 (its hit
  // on frame 3, then walking back forever).
  QTable walkBack(parts.model, g.vertexCount);
  for (std::size_t v = 0; v < g.vertexCount; ++v) walkBack.at(back, v) = 1;
  const PolicyValues retreat = evaluateGreedy(walkBack, g, parts.model, 2, 1e-7);
  CHECK(retreat.q.at(punch, ahead) == Approx(std::pow(gamma, 3)).epsilon(1e-6));
  for (int k = 0; k < 6; ++k) {
    INFO("the centre line's vertex at " << 0.5 * (k + 1) << " m");
    CHECK(retreat.q.at(back, centre(*parts.grid, k)) == 0);
    CHECK(retreat.q.at(forward, centre(*parts.grid, k)) == 0);
  }
  // No policy beats the optimum anywhere, and the optimum's gain over this one is real:
  // punching in place forever at 0.5 m is worth gamma^3 / (1 - gamma^5) there.
  for (std::size_t i = 0; i < retreat.q.values().size(); ++i)
    REQUIRE(retreat.q.values()[i] <= vi.table.values()[i] + 1e-5F);
  CHECK(vi.table.at(punch, ahead) - retreat.q.at(punch, ahead) ==
        Approx(std::pow(gamma, 3) / (1 - std::pow(gamma, 5)) * std::pow(gamma, 5)).epsilon(1e-4));
  CHECK(meanAdvantageOver(vi.table, retreat.q, walkBack) > 0.1);

  // From another start (the optimum's values) the same values, up to the tolerance.
  const PolicyValues fromOptimum = evaluateGreedy(walkBack, g, parts.model, 2, 1e-7, 2000, &vi.table);
  for (std::size_t i = 0; i < retreat.q.values().size(); ++i)
    REQUIRE(fromOptimum.q.values()[i] == Approx(retreat.q.values()[i]).margin(1e-5));
  CHECK_THROWS_WITH(evaluateGreedy(walkBack, g, parts.model, 2, 1e-7, 2000, &small),
                    Catch::Contains("expected a start table of 3 actions x 54 vertices, found 3 x 10"));

  // The same bytes on one thread, and from the compact model.
  const PolicyValues alone = evaluateGreedy(walkBack, g, parts.model, 1, 1e-7);
  CHECK(alone.sweeps == retreat.sweeps);
  CHECK(std::equal(alone.q.values().begin(), alone.q.values().end(), retreat.q.values().begin()));
  const GridModel compact = GridModel::buildCompact(parts.problem, 2);
  const PolicyValues fromCompact = evaluateGreedy(walkBack, compact, parts.model, 2, 1e-7);
  CHECK(std::equal(fromCompact.q.values().begin(), fromCompact.q.values().end(), retreat.q.values().begin()));
}

TEST_CASE("policy evaluation refuses a table of another layout and a model without its transitions, saying which",
          "[learning][opponent]") {
  const CorridorSetup parts(1);
  const QTable small(parts.model, 10);
  CHECK_THROWS_WITH(evaluateGreedy(small, parts.tabulated, parts.model, 1, 1e-3),
                    Catch::Contains("expected a table of 3 actions x 54 vertices, found 3 x 10"));
  CHECK_THROWS_WITH(meanAdvantageOver(QTable(parts.model, 54), QTable(parts.model, 54), small),
                    Catch::Contains("expected three tables of one layout"));
  const GridModel frame = GridModel::frame(parts.problem);
  CHECK_THROWS_WITH(evaluateGreedy(QTable(parts.model, 54), frame, parts.model, 1, 1e-3),
                    Catch::Contains("expected a tabulated or compact model, found the model's frame only"));
}

}  // namespace mgrl::learning_test
