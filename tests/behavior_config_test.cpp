// Behaviours from scenario YAML (DESIGN.md sec. 4-5): every mistake in a `behaviors:` entry
// or a --set override is a ConfigError `file:line:col: key.path: problem` that says what was
// expected; the behaviour key follows what changes the trained table and nothing else; and
// `mgrl list` documents every plugin.
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "app/plugins.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/motion/roles.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace behavior_config_test {

using namespace mgrl;
using Catch::Contains;
using Catch::Equals;
using Catch::StartsWith;
using Catch::EndsWith;

// Both halves of the config error contract: the type and the whole message.
#define REQUIRE_CONFIG_ERROR(expr, message)              \
  do {                                                   \
    REQUIRE_THROWS_AS(expr, ::mgrl::ConfigError);        \
    REQUIRE_THROWS_WITH(expr, ::Catch::Equals(message)); \
  } while (false)

namespace {

// A scenario file that does not exist: motion paths resolve in the data folder, and messages
// start with this path.
const std::filesystem::path kSource = std::filesystem::path(MGRL_SOURCE_DIR) / "tests" / "data" / "behaviors.yaml";

// Lines 1-5 of every scenario below; the `behaviors:` entries start on line 6.
const std::string kHeader =
    "name: cfg\n"
    "motion:\n"
    "  files: [cmu/bvh/13_17_boxing.bvh]\n"
    "graph: {}\n"
    "behaviors:\n";

// Two behaviours shaped like the paper's (sec. 6.4). The approach block is in block style so
// that every key has a line of its own; the comments give the line numbers in the document.
const std::string kApproach =
    "  approach:\n"               // 6
    "    description: walk up\n"  // 7
    "    weight: 1\n"             // 8
    "    activation: always\n"    // 9
    "    discretizer:\n"          // 10
    "      type: polar2d\n"       // 11
    "      radius: 2.0\n"         // 12
    "      rings: 5\n"            // 13
    "      sectors: 13\n"         // 14
    "    reward:\n"               // 15
    "      type: approach\n"      // 16
    "      sigma: 0.1\n"          // 17
    "      gamma: 0.97\n"         // 18
    "    learner:\n"              // 19
    "      type: q_learning\n"    // 20
    "      budget: 1000\n"        // 21
    "      seed: 1\n"             // 22
    "      curve_points: 4\n";    // 23
const std::string kHit =
    "  hit:\n"                                                                       // 24
    "    activation: target_inside\n"                                                // 25
    "    discretizer: {type: cylindrical3d, angles: 4, distances: 3, heights: 2}\n"  // 26
    "    reward: {type: hit, contact_radius: 0.15}\n"                                // 27
    "    environment: {type: static_target}\n"                                       // 28
    "    learner: {type: value_iteration, tolerance: 0.001}\n";                      // 29

const std::string kGraphKey = "0123456789abcdef";

// "<source>:line:col: rest", the start of every located message.
std::string at(int line, int column, const std::string& rest) {
  std::ostringstream s;
  s << kSource.string() << ':' << line << ':' << column << ": " << rest;
  return s.str();
}

// A tiny but valid state-action model: one clip of 6 frames, states at frames 0 and 3, three
// actions (0 -> 1, 0 -> 0, 1 -> 0) and `hitCount` effective hits spread in angle, distance
// and height so that `bounds: hits` has a volume to take.
StateActionModel tinyModel(std::size_t hitCount = 3) {
  StateActionModel m;
  m.frameTime = 1.0 / 30;
  m.framesTotal = 6;
  m.clipOffset = {0, 6};
  m.componentFrames = {0, 1, 2, 3, 4, 5};
  m.transitions = {5, 0};
  m.transitionDistance = {0.2f};
  m.stateFrame = {0, 3};
  m.actionFrom = {0, 0, 1};
  m.actionTo = {1, 0, 0};
  const std::vector<std::vector<std::uint32_t>> frames = {{1, 2, 3}, {1, 2, 3, 4, 5, 0}, {4, 5, 0}};
  m.stateActionBegin = {0, 2, 3};
  m.actionFrameBegin = {0};
  for (std::size_t a = 0; a < frames.size(); ++a) {
    const double dz = 0.1 * static_cast<double>(frames[a].size());
    m.actionDisplacement.insert(m.actionDisplacement.end(), {0.0, dz, 0.0});
    for (std::size_t t = 0; t < frames[a].size(); ++t) {
      const double f = static_cast<double>(t + 1) / static_cast<double>(frames[a].size());
      m.actionFrames.push_back(frames[a][t]);
      m.frameRoot.insert(m.frameRoot.end(), {0.0, f * dz, 0.0});
      m.frameCentroid.insert(m.frameCentroid.end(), {0.0f, 1.2f, static_cast<float>(0.4 + f * dz)});
      m.frameEntersTransition.push_back(frames[a][t] == 0 ? 1 : 0);
    }
    m.actionFrameBegin.push_back(static_cast<std::uint32_t>(m.actionFrames.size()));
  }
  const std::vector<ActionHit> hits = {
      {0, 2, 0, 0.2f, 1.1f, 0.5f, 0.8f}, {1, 4, 1, -0.3f, 1.4f, 0.7f, 1.0f}, {2, 1, 0, 0.0f, 1.6f, 0.4f, 0.5f}};
  m.actionHitBegin = {0};
  for (std::size_t a = 0; a < frames.size(); ++a) {
    for (std::size_t h = 0; h < hitCount && h < hits.size(); ++h)
      if (hits[h].action == a) m.hits.push_back(hits[h]);
    m.actionHitBegin.push_back(static_cast<std::uint32_t>(m.hits.size()));
  }
  m.centroid[1] = 1.3;
  m.centroid[2] = 0.5;
  m.maxHitSpeed_mps = 6;
  // Two joints: the hips (the pelvis role, 1 m up) and a left hand 0.5 m ahead of them,
  // moving at 2 m/s; every other role is the hand too.
  m.jointNames = {"Hips", "LeftHand"};
  for (const std::string& role : roleNames()) m.roleJoint.push_back(role == "pelvis" ? 0 : 1);
  for (std::uint32_t f = 0; f < m.framesTotal; ++f) {
    m.sourceJoint.insert(m.sourceJoint.end(), {0.0f, 1.0f, 0.0f, 0.1f, 1.3f, 0.5f});
    m.sourceJointSpeed.insert(m.sourceJointSpeed.end(), {0.0f, 2.0f});
  }
  checkModel(m, "tinyModel");
  return m;
}

const StateActionModel& model() {
  static const StateActionModel m = tinyModel();
  return m;
}

Scenario parse(const std::string& behaviors, const std::vector<std::string>& overrides = {}) {
  return parseScenario(kHeader + behaviors, kSource, test::mocap(), overrides);
}

std::vector<Behavior> build(const std::string& behaviors, const std::vector<std::string>& overrides = {},
                            const std::string& graphKey = kGraphKey) {
  return buildBehaviors(parse(behaviors, overrides), app::plugins(), model(), graphKey);
}

// kApproach with the line numbered `line` in the document (see kApproach) replaced by `text`
// (without "\n"), or removed when `text` is empty.
std::string approachWith(int line, const std::string& text) {
  std::istringstream in(kApproach);
  std::string result, l;
  for (int n = 6; std::getline(in, l); ++n) {
    if (n != line)
      result += l + "\n";
    else if (!text.empty())
      result += text + "\n";
  }
  return result;
}

// kApproach with `text` inserted as a new line before line `line`.
std::string approachInserting(int line, const std::string& text) {
  std::istringstream in(kApproach);
  std::string result, l;
  for (int n = 6; std::getline(in, l); ++n) {
    if (n == line) result += text + "\n";
    result += l + "\n";
  }
  return result;
}

const Behavior& named(const std::vector<Behavior>& behaviors, const std::string& name) {
  for (const Behavior& b : behaviors)
    if (b.name == name) return b;
  FAIL("no behaviour " << name);
  return behaviors.front();  // not reached: FAIL throws
}

}  // namespace

TEST_CASE("a well-formed behaviors section builds every plugin with defaults filled in", "[behaviors]") {
  const std::vector<Behavior> all = build(kApproach + kHit);
  REQUIRE(all.size() == 2);
  const Behavior& approach = all[0];
  const Behavior& hit = all[1];
  CHECK(approach.name == "approach");
  CHECK(hit.name == "hit");
  CHECK(approach.activation == Activation::Always);
  CHECK(hit.activation == Activation::TargetInside);
  CHECK(approach.discretizer->type() == "polar2d");
  CHECK(approach.discretizer->vertexCount() == 5 * 13);
  CHECK(hit.discretizer->type() == "cylindrical3d");
  CHECK(hit.discretizer->vertexCount() == 4 * 3 * 2);
  CHECK(approach.reward->type() == "approach");
  CHECK(hit.reward->type() == "hit");
  CHECK(approach.learner->type() == "q_learning");
  CHECK(hit.learner->type() == "value_iteration");
  // The config records every parameter, the defaults too, and the implicit environment.
  CHECK(approach.config["learner"]["budget"] == 1000);
  CHECK(approach.config["learner"]["alpha_final"] == 0.0);
  CHECK(approach.config["learner"]["checkpoint_every"] == 10'000'000);
  CHECK(approach.config["discretizer"]["min_radius"] == 0.0);
  CHECK(approach.config["environment"]["type"] == "static_target");
  CHECK(hit.config["reward"]["use_speed"] == true);
  CHECK(hit.config["learner"]["max_sweeps"] == 1000);
  CHECK(approach.key != hit.key);
  CHECK(approach.key.size() >= 16);
}

TEST_CASE("behaviour mistakes name the file, line, column and key", "[behaviors]") {
  REQUIRE_NOTHROW(build(kApproach + kHit));

  SECTION("an unknown key lists the keys a behaviour takes") {
    REQUIRE_CONFIG_ERROR(build(approachWith(8, "    wieght: 1")),
                         at(8, 13,
                            "behaviors.approach.wieght: unknown key (expected one of: description, weight, "
                            "activation, stance, discretizer, reward, environment, learner, success)"));
  }
  SECTION("an unknown plugin type lists the known names, seam by seam") {
    REQUIRE_CONFIG_ERROR(build(approachWith(11, "      type: hexgrid")),
                         at(11, 13,
                            "behaviors.approach.discretizer.type: unknown discretizer 'hexgrid' (known: "
                            "polar2d, cylindrical3d, kd_tree, polar_velocity)"));
    REQUIRE_CONFIG_ERROR(build(approachWith(16, "      type: punch")),
                         at(16, 13, "behaviors.approach.reward.type: unknown reward 'punch' (known: approach, hit, terms)"));
    REQUIRE_CONFIG_ERROR(build(approachWith(20, "      type: sarsa")),
                         at(20, 13,
                            "behaviors.approach.learner.type: unknown learner 'sarsa' (known: q_learning, "
                            "value_iteration, adaptive_value_iteration, mpi_value_iteration)"));
    REQUIRE_CONFIG_ERROR(build(approachInserting(19, "    environment: {type: orbiting_target}")),
                         at(19, 25,
                            "behaviors.approach.environment.type: unknown environment model "
                            "'orbiting_target' (known: static_target, moving_target, opponent, learned_opponent)"));
    REQUIRE_CONFIG_ERROR(build(approachInserting(19, "    environment: {type: moving_target, min_speed: 2, max_speed: 1}")),
                         at(19, 51, "behaviors.approach.environment.min_speed: expected at most max_speed (1 m/s), found 2 m/s"));
    REQUIRE_CONFIG_ERROR(
        build(approachInserting(19, "    environment: {type: moving_target, max_turn_deg_s: 90, turns: 1}")),
        at(19, 67,
           "behaviors.approach.environment.turns: expected at least 2 turn rates with max_turn_deg_s 90 (from -90 to "
           "+90 deg/s), found 1"));
  }
  SECTION("a turning moving_target gives a grid with a heading one layer per turn rate") {
    const std::string turning =
        "  chase:\n"
        "    discretizer: {type: polar_velocity, sectors: 4, rings: 3, headings: 4, speeds: 2}\n"
        "    reward: {type: approach}\n"
        "    environment: {type: moving_target, max_turn_deg_s: 90, turns: 3}\n"
        "    learner: {type: value_iteration}\n";
    const std::vector<Behavior> built = build(turning);
    const Discretizer& grid = *built.front().discretizer;
    REQUIRE(grid.turnAxis() != nullptr);
    CHECK(grid.turnAxis()->vertices == std::vector<double>{-M_PI / 2, 0, M_PI / 2});
    CHECK(grid.vertexCount() == 4 * 3 * 4 * 2 * 3);
    // A grid without a heading (polar2d) cannot tell which way a turn goes: its values
    // average over turns as over headings, with no layers.
    CHECK(build(approachInserting(19, "    environment: {type: moving_target, max_turn_deg_s: 90, turns: 3}"))
              .front()
              .discretizer->turnAxis() == nullptr);
  }
  SECTION("an opponent needs a grid with a heading axis; avoid needs an opponent") {
    const std::string dodge =
        "  dodge:\n"                                                               // 6
        "    discretizer: {type: polar_velocity, speeds: 1, headings: 4}\n"        // 7
        "    reward: {type: terms, terms: [{term: avoid}, {term: facing}]}\n"      // 8
        "    environment: {type: opponent}\n"                                      // 9
        "    learner: {type: value_iteration}\n"                                   // 10
        "    success: {term: avoid, clear: 0.1, hold_s: 1}\n";                     // 11
    REQUIRE_NOTHROW(build(dodge));
    std::string onPolar2d = dodge;
    onPolar2d.replace(onPolar2d.find("polar_velocity, speeds: 1, headings: 4"), 38, "polar2d");
    REQUIRE_CONFIG_ERROR(build(onPolar2d),
                         at(9, 25,
                            "behaviors.dodge.environment.type: expected a grid with a heading axis to hold the "
                            "opponent's facing (polar_velocity with speeds: 1), found polar2d"));
    std::string still = dodge;
    still.replace(still.find("opponent"), 8, "static_target");
    REQUIRE_CONFIG_ERROR(build(still),
                         at(8, 42,
                            "behaviors.dodge.reward.terms[0].term: expected environment: {type: opponent} or "
                            "learned_opponent (the avoid term reads the opponent's strikes), found static_target"));
    // The strikes it takes read them too.
    std::string struck = still;
    struck.replace(struck.find("{term: avoid}"), 13, "{term: struck}");
    REQUIRE_CONFIG_ERROR(build(struck),
                         at(8, 42,
                            "behaviors.dodge.reward.terms[0].term: expected environment: {type: opponent} or "
                            "learned_opponent (the struck term reads the opponent's strikes), found static_target"));
    std::string successOnly = still;
    successOnly.replace(successOnly.find("{term: avoid}, "), 15, "");
    REQUIRE_CONFIG_ERROR(build(successOnly),
                         at(11, 14,
                            "behaviors.dodge.success: expected environment: {type: opponent} (the avoid term "
                            "reads the opponent's strikes), found static_target"));
  }
  SECTION("an unknown plugin parameter lists the plugin's parameters") {
    REQUIRE_CONFIG_ERROR(build(approachWith(13, "      rigns: 5")),
                         at(13, 14,
                            "behaviors.approach.discretizer.rigns: unknown key (expected one of: type, "
                            "radius, min_radius, rings, sectors, angle_min, angle_max)"));
    REQUIRE_CONFIG_ERROR(build(approachWith(22, "      sead: 1")),
                         at(22, 13,
                            "behaviors.approach.learner.sead: unknown key (expected one of: type, budget, "
                            "seed, alpha_final, curve_points, curve_sample, checkpoint_every, max_episode_actions, threads)"));
    REQUIRE_CONFIG_ERROR(build(approachInserting(19, "    environment: {type: static_target, speed: 1}")),
                         at(19, 47,
                            "behaviors.approach.environment.speed: unknown key (this plugin takes no parameters; "
                            "expected only: type)"));
  }
  SECTION("a parameter of the wrong type") {
    REQUIRE_CONFIG_ERROR(build(approachWith(21, "      budget: lots")),
                         at(21, 15,
                            "behaviors.approach.learner.budget: expected a whole number in [1, "
                            "1000000000000], found 'lots'"));
    REQUIRE_CONFIG_ERROR(build(approachWith(13, "      rings: 2.5")),
                         at(13, 14,
                            "behaviors.approach.discretizer.rings: expected a whole number in [2, 10000], "
                            "found '2.5'"));
    REQUIRE_CONFIG_ERROR(build(kApproach + "  hit:\n    discretizer: {type: cylindrical3d}\n    reward: {type: hit, "
                                           "use_speed: fast}\n    learner: {type: value_iteration}\n"),
                         at(26, 36, "behaviors.hit.reward.use_speed: expected true or false, found 'fast'"));
  }
  SECTION("a parameter out of its range") {
    REQUIRE_CONFIG_ERROR(build(approachWith(17, "      sigma: -1")),
                         at(17, 14, "behaviors.approach.reward.sigma: expected a number in [0.0001, 100], found -1"));
    REQUIRE_CONFIG_ERROR(build(approachWith(13, "      rings: 1")),
                         at(13, 14,
                            "behaviors.approach.discretizer.rings: expected a whole number in [2, 10000], "
                            "found 1"));
    REQUIRE_CONFIG_ERROR(build(approachWith(18, "      gamma: 1.5")),
                         at(18, 14, "behaviors.approach.reward.gamma: expected a number in [1e-06, 1], found 1.5"));
    REQUIRE_CONFIG_ERROR(build(approachWith(21, "      budget: 0")),
                         at(21, 15,
                            "behaviors.approach.learner.budget: expected a whole number in [1, "
                            "1000000000000], found 0"));
  }
  SECTION("a choice outside its set") {
    REQUIRE_CONFIG_ERROR(
        build(kApproach + "  hit:\n    discretizer: {type: cylindrical3d, bounds: box}\n    reward: {type: hit}\n"
                          "    learner: {type: value_iteration}\n"),
        at(25, 48, "behaviors.hit.discretizer.bounds: expected one of: hits, given, found 'box'"));
  }
  SECTION("parameters that contradict each other") {
    // polar2d: the inner ring must lie inside the outer one.
    REQUIRE_CONFIG_ERROR(build(approachInserting(13, "      min_radius: 2.5")),
                         at(13, 19,
                            "behaviors.approach.discretizer.min_radius: expected less than radius (2 m), "
                            "found 2.5 m"));
    REQUIRE_CONFIG_ERROR(build(approachInserting(13, "      min_radius: 2")),
                         at(13, 19,
                            "behaviors.approach.discretizer.min_radius: expected less than radius (2 m), "
                            "found 2 m"));
    // cylindrical3d, bounds given: at the key given, or at the block when the other bound
    // is the defaulted one.
    const std::string hitHead = "  hit:\n    discretizer: {type: cylindrical3d, bounds: given, ";
    const std::string hitTail = "}\n    reward: {type: hit}\n    learner: {type: value_iteration}\n";
    REQUIRE_CONFIG_ERROR(build(kApproach + hitHead + "distance_min: 0.8, distance_max: 0.5" + hitTail),
                         at(25, 88,
                            "behaviors.hit.discretizer.distance_max: expected more than distance_min (0.8 m), "
                            "found 0.5 m"));
    REQUIRE_CONFIG_ERROR(build(kApproach + hitHead + "distance_min: 1.5" + hitTail),
                         at(25, 18,
                            "behaviors.hit.discretizer: distance_max: expected more than distance_min (1.5 m), "
                            "found 1 m"));
    REQUIRE_CONFIG_ERROR(build(kApproach + hitHead + "height_min: 1.8" + hitTail),
                         at(25, 18,
                            "behaviors.hit.discretizer: height_max: expected more than height_min (1.8 m), "
                            "found 1.8 m"));
    REQUIRE_CONFIG_ERROR(build(kApproach + hitHead + "angle_min: -200, angle_max: 170" + hitTail),
                         at(25, 83,
                            "behaviors.hit.discretizer.angle_max: expected at most 360 degrees above "
                            "angle_min"));
    // A key the chosen bounds do not read is refused, not ignored.
    const std::string hitsHead = "  hit:\n    discretizer: {type: cylindrical3d, bounds: hits, ";
    REQUIRE_CONFIG_ERROR(build(kApproach + hitsHead + "distance_min: 5, distance_max: 0.1" + hitTail),
                         at(25, 68,
                            "behaviors.hit.discretizer.distance_min: expected no distance_min with bounds: hits (it "
                            "applies to bounds: given only); remove it or set bounds: given"));
    REQUIRE_CONFIG_ERROR(build(kApproach + hitHead + "margin: 0.1" + hitTail),
                         at(25, 63,
                            "behaviors.hit.discretizer.margin: expected no margin with bounds: given (it applies to "
                            "bounds: hits only); remove it or set bounds: hits"));
  }
  SECTION("missing sections and blocks without a type") {
    REQUIRE_CONFIG_ERROR(build("  approach:\n    discretizer: {type: polar2d}\n    learner: {type: q_learning}\n"),
                         at(7, 5, "behaviors.approach: expected a 'reward' section, found none"));
    REQUIRE_CONFIG_ERROR(build("  approach:\n    reward: {type: approach}\n    learner: {type: q_learning}\n"),
                         at(7, 5, "behaviors.approach: expected a 'discretizer' section, found none"));
    REQUIRE_CONFIG_ERROR(build("  approach:\n    discretizer: {type: polar2d}\n    reward: {type: approach}\n"),
                         at(7, 5, "behaviors.approach: expected a 'learner' section, found none"));
    REQUIRE_CONFIG_ERROR(build(approachWith(20, "")),
                         at(20, 7,
                            "behaviors.approach.learner: expected a 'type' key naming the learner "
                            "(q_learning, value_iteration, adaptive_value_iteration, mpi_value_iteration)"));
    REQUIRE_CONFIG_ERROR(build(approachWith(16, "")),
                         at(16, 7,
                            "behaviors.approach.reward: expected a 'type' key naming the reward (approach, "
                            "hit, terms)"));
    REQUIRE_CONFIG_ERROR(build(approachInserting(19, "    environment: {}")),
                         at(19, 18,
                            "behaviors.approach.environment: expected a 'type' key naming the environment "
                            "model (static_target, moving_target, opponent, learned_opponent)"));
    REQUIRE_CONFIG_ERROR(build(approachInserting(19, "    environment: static_target")),
                         at(19, 18,
                            "behaviors.approach.environment: expected a map with 'type: static_target' or "
                            "another environment model"));
    REQUIRE_CONFIG_ERROR(
        build("  approach:\n    discretizer: {type: polar2d}\n    reward: approach\n    learner: {type: q_learning}\n"),
        at(8, 13, "behaviors.approach.reward: expected a map, found 'approach'"));
  }
  SECTION("a bad activation rule") {
    REQUIRE_CONFIG_ERROR(build(approachWith(9, "    activation: sometimes")),
                         at(9, 17,
                            "behaviors.approach.activation: expected an activation rule (always, "
                            "target_inside), found 'sometimes'"));
  }
  SECTION("stances numbered with a gap, or out of range") {
    // Stances number 0..N-1, each held by a behaviour.
    REQUIRE_CONFIG_ERROR(build(approachWith(9, "    stance: 2")),
                         at(9, 13,
                            "behaviors.approach.stance: expected stances numbered 0..2 with a behaviour for each, "
                            "found none for stance 0"));
    // A stance's facing term must be its behaviour's and count the scenario's stances.
    const std::string stanceTerm =
        "  keep:\n    stance: 0\n    discretizer: {type: polar2d}\n    reward: {type: terms, terms: [{term: facing, "
        "prefer: stance, stance: 1, stances: 1}]}\n    learner: {type: value_iteration}\n";
    REQUIRE_THROWS_WITH(build(stanceTerm), Catch::Contains("behaviors.keep.reward.terms[0].stance: expected the "
                                                           "behaviour's stance, 0, found 1"));
    std::string counted = stanceTerm;
    counted.replace(counted.find("stance: 1, stances: 1"), 21, "stance: 0, stances: 3");
    REQUIRE_THROWS_WITH(build(counted), Catch::Contains("behaviors.keep.reward.terms[0].stances: expected the "
                                                        "scenario's number of stances, 1, found 3"));
    std::string unheld = counted;
    unheld.replace(unheld.find("    stance: 0\n"), 14, "");
    REQUIRE_THROWS_WITH(build(unheld), Catch::Contains("behaviors.keep.reward.terms[0].prefer: expected the behaviour "
                                                       "to hold a stance"));
    std::string fine = counted;
    fine.replace(fine.find("stances: 3"), 10, "stances: 1");
    CHECK(build(fine).front().stance == 0);
    REQUIRE_THROWS_WITH(build(approachWith(9, "    stance: 16")),
                        Catch::Contains("behaviors.approach.stance") && Catch::Contains("16"));
    REQUIRE_THROWS_WITH(build(approachWith(9, "    stance: -1")),
                        Catch::Contains("behaviors.approach.stance") && Catch::Contains("-1"));
  }
  SECTION("a behaviour name that cannot name a file") {
    REQUIRE_CONFIG_ERROR(build(approachWith(6, "  \"a/b\":")),
                         at(7, 5,
                            "behaviors.a/b: expected a behaviour name of letters, digits, '_' and '-' (it "
                            "names files of the policy bundle)"));
    REQUIRE_CONFIG_ERROR(build(approachWith(6, "  \"two words\":")),
                         at(7, 5,
                            "behaviors.two words: expected a behaviour name of letters, digits, '_' and '-' "
                            "(it names files of the policy bundle)"));
  }
  SECTION("a behaviour or a behaviors section of the wrong shape") {
    REQUIRE_CONFIG_ERROR(build("  approach: 3\n"),
                         at(6, 13, "behaviors.approach: expected a map with discretizer, reward and learner sections"));
    REQUIRE_CONFIG_ERROR(
        parseScenario(kHeader.substr(0, kHeader.size() - 1) + " [approach, hit]\n", kSource, test::mocap()),
        at(5, 12, "behaviors: expected a map, found a list"));
  }
  SECTION("no behaviour to build") {
    const Scenario none =
        parseScenario("motion:\n  files: [cmu/bvh/13_17_boxing.bvh]\ngraph: {}\n", kSource, test::mocap());
    CHECK(none.behaviors.empty());
    REQUIRE_CONFIG_ERROR(buildBehaviors(none, app::plugins(), model(), kGraphKey),
                         at(1, 1, "expected a 'behaviors' section naming at least one behaviour to train, found none"));
    const Scenario empty = parse("  {}\n");
    CHECK(empty.behaviors.empty());
    REQUIRE_THROWS_AS(buildBehaviors(empty, app::plugins(), model(), kGraphKey), ConfigError);
  }
  SECTION("--behavior names one of the scenario's behaviours") {
    const Scenario s = parse(kApproach + kHit);
    const std::vector<Behavior> only = buildBehaviors(s, app::plugins(), model(), kGraphKey, "hit");
    REQUIRE(only.size() == 1);
    CHECK(only[0].name == "hit");
    REQUIRE_THROWS_AS(buildBehaviors(s, app::plugins(), model(), kGraphKey, "nope"), Error);
    REQUIRE_THROWS_WITH(buildBehaviors(s, app::plugins(), model(), kGraphKey, "nope"),
                        Equals("--behavior: expected one of the scenario's behaviours (approach, hit), found 'nope'"));
  }
  SECTION("bounds: hits needs effective hits in the graph") {
    const StateActionModel oneHit = tinyModel(1);
    const Scenario s = parse(kApproach + kHit);
    REQUIRE_CONFIG_ERROR(buildBehaviors(s, app::plugins(), oneHit, kGraphKey),
                         at(26, 18,
                            "behaviors.hit.discretizer: bounds: expected at least 2 effective hitting points "
                            "in the graph's actions to take the bounds from, found 1; set bounds: given with "
                            "angle_min ... height_max"));
  }
}

TEST_CASE("scenario overrides (--set) replace, create and reset keys", "[behaviors]") {
  const std::string both = kApproach + kHit;

  SECTION("a value replaces the file's") {
    const auto all = build(both, {"behaviors.approach.reward.sigma=0.25", "behaviors.hit.learner.tolerance=0.01",
                                  "behaviors.approach.weight=2.5", "behaviors.approach.activation=target_inside"});
    CHECK(named(all, "approach").config["reward"]["sigma"] == 0.25);
    CHECK(named(all, "approach").weight == 2.5);
    CHECK(named(all, "approach").activation == Activation::TargetInside);
    CHECK(named(all, "hit").config["learner"]["tolerance"] == 0.01);
  }
  SECTION("a missing key or section is created") {
    const auto all = build(both, {"behaviors.approach.learner.alpha_final=0.5", "behaviors.hit.reward.use_speed=false",
                                  "behaviors.hit.description=punch"});
    CHECK(named(all, "approach").config["learner"]["alpha_final"] == 0.5);
    CHECK(named(all, "hit").config["reward"]["use_speed"] == false);
    // A behaviour filled in by overrides.
    const auto extra = build(both + "  extra: {discretizer: {}, reward: {}, learner: {}}\n",
                             {"behaviors.extra.discretizer.type=polar2d", "behaviors.extra.reward.type=hit",
                              "behaviors.extra.learner.type=value_iteration"});
    REQUIRE(extra.size() == 3);
    CHECK(extra[2].name == "extra");
    CHECK(extra[2].reward->type() == "hit");
  }
  SECTION("another type drops the old type's parameters, the same type keeps them") {
    // budget and seed are q_learning's: kept, value_iteration would reject them.
    REQUIRE_CONFIG_ERROR(build(approachWith(20, "      type: value_iteration")),
                         at(21, 15,
                            "behaviors.approach.learner.budget: unknown key (expected one of: type, tolerance, "
                            "max_sweeps, threads)"));
    const auto switched = build(both, {"behaviors.approach.learner.type=value_iteration"});
    const Behavior& approach = named(switched, "approach");
    CHECK(approach.learner->type() == "value_iteration");
    CHECK_FALSE(approach.config["learner"].contains("budget"));
    CHECK(approach.config["learner"]["tolerance"] == 1e-4);
    // The rest of the behaviour is untouched.
    CHECK(approach.config["reward"]["sigma"] == 0.1);

    const auto same = build(both, {"behaviors.approach.learner.type=q_learning"});
    CHECK(named(same, "approach").config["learner"]["budget"] == 1000);
    // Later overrides add the new type's parameters.
    const auto tuned =
        build(both, {"behaviors.approach.learner.type=value_iteration", "behaviors.approach.learner.max_sweeps=7"});
    CHECK(named(tuned, "approach").config["learner"]["max_sweeps"] == 7);
  }
  SECTION("overridden values are checked like the file's") {
    REQUIRE_THROWS_WITH(build(both, {"behaviors.approach.learner.budget=lots"}),
                        Contains("behaviors.approach.learner.budget: expected a whole number in [1, 1000000000000], "
                                 "found 'lots'"));
    // Named at the flag that set it, not at the file's line.
    REQUIRE_CONFIG_ERROR(build(both, {"behaviors.approach.learner.bugdet=5"}),
                         std::string("--set behaviors.approach.learner.bugdet=5") +
                             ": behaviors.approach.learner.bugdet: unknown key (expected one of: type, "
                             "budget, seed, alpha_final, curve_points, curve_sample, checkpoint_every, max_episode_actions, threads)");
    REQUIRE_CONFIG_ERROR(build(both, {"behaviors.approach.learner.type=sarsa"}),
                         std::string("--set behaviors.approach.learner.type=sarsa") +
                             ": behaviors.approach.learner.type: unknown learner 'sarsa' (known: "
                             "q_learning, value_iteration, adaptive_value_iteration, mpi_value_iteration)");
    REQUIRE_CONFIG_ERROR(build(both, {"grpah=0.3"}),
                         std::string("--set grpah=0.3") +
                             ": grpah: unknown key (expected one of: name, description, motion, graph, "
                             "behaviors, world, sparring_scenario)");
    REQUIRE_THROWS_WITH(build(both, {"behaviors.hit=3"}),
                        Contains("behaviors.hit: expected a map with discretizer, reward and learner sections"));
  }
  SECTION("malformed overrides say what was expected") {
    const std::string source = kSource.string();
    REQUIRE_CONFIG_ERROR(parse(both, {"nokey"}), source +
                                                     ": --set 'nokey': expected KEY=VALUE with a dotted KEY such as "
                                                     "behaviors.hit.learner.budget");
    REQUIRE_CONFIG_ERROR(parse(both, {"=3"}), source +
                                                  ": --set '=3': expected KEY=VALUE with a dotted KEY such as "
                                                  "behaviors.hit.learner.budget");
    REQUIRE_CONFIG_ERROR(parse(both, {"a..b=1"}), source + ": --set a..b: expected a dotted key without empty parts");
    REQUIRE_CONFIG_ERROR(parse(both, {".a=1"}), source + ": --set .a: expected a dotted key without empty parts");
    REQUIRE_CONFIG_ERROR(parse(both, {"a.=1"}), source + ": --set a.: expected a dotted key without empty parts");
    REQUIRE_CONFIG_ERROR(parse(both, {"name.x=1"}),
                         source + ": --set name.x: expected 'name' to be a map, found a value");
    REQUIRE_CONFIG_ERROR(parse(both, {"behaviors.approach.weight.x=1"}),
                         source +
                             ": --set behaviors.approach.weight.x: expected 'behaviors.approach.weight' to be a "
                             "map, found a value");
  }
}

TEST_CASE("an override (--set) names an element of a list by its index", "[behaviors]") {
  const std::string keep =
      "  keep:\n"
      "    discretizer: {type: polar2d, radius: 2.0}\n"
      "    reward: {type: terms, combine: sum, terms: [{term: distance, point: pelvis, d0: 1}, {term: facing}]}\n"
      "    learner: {type: value_iteration}\n";
  const std::vector<Behavior> plain = build(keep);
  const std::vector<Behavior> set = build(keep, {"behaviors.keep.reward.terms[1].weight=2",
                                                 "behaviors.keep.reward.terms[0].d0=1.5"});
  CHECK(set[0].config["reward"]["terms"][1]["weight"] == 2.0);
  CHECK(set[0].config["reward"]["terms"][1]["term"] == "facing");  // the element's other keys stay
  CHECK(set[0].config["reward"]["terms"][0]["d0"] == 1.5);
  CHECK(plain[0].config["reward"]["terms"][1]["weight"] == 1.0);
  CHECK(set[0].key != plain[0].key);
  // A bad value is reported at the --set that gave it, with the element's path.
  REQUIRE_CONFIG_ERROR(build(keep, {"behaviors.keep.reward.terms[1].weight=-1"}),
                       "--set behaviors.keep.reward.terms[1].weight=-1: behaviors.keep.reward.terms[1].weight: "
                       "expected a number in [0, 1000], found -1");
  const std::string source = kSource.string() + ": --set ";
  REQUIRE_CONFIG_ERROR(parse(keep, {"behaviors.keep.reward.terms[2].weight=1"}),
                       source + "behaviors.keep.reward.terms[2].weight: expected an index below 2 "
                                "('behaviors.keep.reward.terms' has 2 elements), found 2");
  REQUIRE_CONFIG_ERROR(parse(keep, {"behaviors.keep.reward.terms[x].weight=1"}),
                       source + "behaviors.keep.reward.terms[x].weight: expected a list index such as terms[0], "
                                "found 'terms[x]'");
  REQUIRE_CONFIG_ERROR(parse(keep, {"behaviors.keep.reward.terms[1.weight=1"}),
                       source + "behaviors.keep.reward.terms[1.weight: expected a list index such as terms[0], "
                                "found 'terms[1'");
  REQUIRE_CONFIG_ERROR(parse(keep, {"behaviors.keep.reward.terms.weight=1"}),
                       source + "behaviors.keep.reward.terms.weight: expected 'behaviors.keep.reward.terms' to be "
                                "a map, found a list (name an element: KEY[0])");
  REQUIRE_CONFIG_ERROR(parse(keep, {"behaviors.keep.reward[0].type=hit"}),
                       source + "behaviors.keep.reward[0].type: expected 'behaviors.keep.reward' to be a list, "
                                "found a map or a value");
  REQUIRE_CONFIG_ERROR(parse(keep, {"behaviors.keep.reward.gamma[0]=1"}),
                       source + "behaviors.keep.reward.gamma[0]: expected 'behaviors.keep.reward.gamma' to be a "
                                "list, found nothing");
}

// scenario.hpp: "KEY is a dotted path (...), created if missing". Only the last part is: a
// missing map on the way is an undefined yaml-cpp node, neither a map nor null, and
// applyOverride refuses it as "a value" (so a typo like grpah.threshold is misreported too).
TEST_CASE("an override (--set) creates missing sections along its path", "[behaviors]") {
  const std::string both = kApproach + kHit;
  CHECK_NOTHROW(build(both, {"behaviors.approach.environment.type=static_target"}));
  std::vector<Behavior> all;
  REQUIRE_NOTHROW(all = build(both, {"behaviors.extra.discretizer.type=polar2d", "behaviors.extra.reward.type=hit",
                                     "behaviors.extra.learner.type=value_iteration"}));
  CHECK(all.size() == 3);
  REQUIRE_THROWS_WITH(build(both, {"grpah.threshold=0.3"}),
                      Equals(kSource.string() + ": grpah: unknown key (expected one of: name, description, motion, "
                                                "graph, behaviors, world, sparring_scenario)"));
}

// The help of `mgrl train --set` shows `--set behaviors.hit.learner.budget=1e6`; budget is a
// whole number and YAML's integer conversion rejects "1e6", so the example fails.
TEST_CASE("the --set example of mgrl train --help is accepted", "[behaviors]") {
  const auto all = build(kApproach + kHit, {"behaviors.approach.learner.budget=1e6"});
  CHECK(named(all, "approach").config["learner"]["budget"] == 1000000);
}

// A later `type=` override resets the block, dropping keys an earlier --set just gave: the
// user's explicit value is then silently replaced by the default.
TEST_CASE("a --set before a type switch is not silently lost", "[behaviors]") {
  const std::vector<std::string> overrides = {"behaviors.approach.learner.tolerance=0.01",
                                              "behaviors.approach.learner.type=value_iteration"};
  // Type switches apply first (scenario.cpp), so the --set before one is kept, in either
  // order, and nothing is refused.
  std::vector<Behavior> all;
  REQUIRE_NOTHROW(all = build(kApproach + kHit, overrides));
  CHECK(named(all, "approach").config["learner"]["type"] == "value_iteration");
  CHECK(named(all, "approach").config["learner"]["tolerance"] == 0.01);
  REQUIRE_NOTHROW(all = build(kApproach + kHit, {overrides[1], overrides[0]}));
  CHECK(named(all, "approach").config["learner"]["tolerance"] == 0.01);
}

// yaml-cpp keeps both entries of a key written twice, and ConfigNode::child() returns the
// first: the second behaviour block or parameter is silently ignored (a second `approach:`
// even yields two behaviours of that name, both built from the first block).
TEST_CASE("a key written twice in a behaviour is an error", "[behaviors]") {
  CHECK_THROWS_AS(build(approachInserting(14, "      rings: 3")), ConfigError);
  CHECK_THROWS_WITH(build(approachInserting(14, "      rings: 3")), Contains("behaviors.approach.discretizer.rings"));
  const std::string twice = kApproach +
                            "  approach:\n    discretizer: {type: polar2d}\n    reward: {type: approach}\n"
                            "    learner: {type: value_iteration}\n";
  CHECK_THROWS_AS(parse(twice), ConfigError);
}

TEST_CASE("the behaviour key changes with what the table depends on, and only that", "[behaviors]") {
  const std::string both = kApproach + kHit;
  const std::string base = named(build(both), "approach").key;
  const std::string baseHit = named(build(both), "hit").key;
  CHECK(named(build(both), "approach").key == base);  // a function of its inputs

  auto keyWith = [&](const std::string& set) {
    CAPTURE(set);
    return named(build(both, {set}), "approach").key;
  };
  SECTION("learner, reward, discretizer and graph change it") {
    for (const char* set :
         {"behaviors.approach.learner.budget=1001", "behaviors.approach.learner.seed=2",
          "behaviors.approach.learner.alpha_final=0.1", "behaviors.approach.learner.type=value_iteration",
          "behaviors.approach.reward.sigma=0.2", "behaviors.approach.reward.gamma=0.9",
          "behaviors.approach.discretizer.rings=6", "behaviors.approach.discretizer.radius=2.5"}) {
      CAPTURE(set);
      CHECK(keyWith(set) != base);
    }
    CHECK(named(build(both, {}, "fedcba9876543210"), "approach").key != base);
    const auto vi = build(both, {"behaviors.hit.learner.tolerance=0.002"});
    CHECK(named(vi, "hit").key != baseHit);
    CHECK(named(vi, "approach").key == base);
  }
  SECTION("weight, activation, description, threads, curve_points and checkpoint_every do not") {
    for (const char* set :
         {"behaviors.approach.weight=3", "behaviors.approach.activation=target_inside", "behaviors.approach.stance=0",
          "behaviors.approach.description=other", "behaviors.approach.learner.threads=1",
          "behaviors.approach.learner.curve_points=50", "behaviors.approach.learner.checkpoint_every=1000"}) {
      CAPTURE(set);
      CHECK(keyWith(set) == base);
    }
    CHECK(named(build(both, {"behaviors.hit.learner.threads=2"}), "hit").key == baseHit);
    CHECK(named(build(both, {"behaviors.hit.weight=0.5"}), "hit").key == baseHit);
  }
  SECTION("effort's default point (pelvis, the root's speed) keeps the key effort terms had before points") {
    auto keyOf = [&](const std::string& terms) {
      return build("  keep:\n    discretizer: {type: polar2d}\n    reward: {type: terms, terms: [" + terms +
                   "]}\n    learner: {type: value_iteration}\n").front().key;
    };
    CHECK(keyOf("{term: effort}") == keyOf("{term: effort, point: pelvis}"));
    CHECK(keyOf("{term: effort}") != keyOf("{term: effort, point: body}"));
    CHECK(keyOf("{term: effort}") != keyOf("{term: effort, point: LeftHand}"));
  }
  SECTION("facing's stance and stances count in the key only with prefer: stance") {
    auto keyOf = [&](const std::string& terms) {
      return build("  keep:\n    discretizer: {type: polar2d}\n    reward: {type: terms, terms: [" + terms +
                   "]}\n    learner: {type: value_iteration}\n")
          .front()
          .key;
    };
    CHECK(keyOf("{term: facing}") == keyOf("{term: facing, stance: 2, stances: 5}"));
    CHECK(keyOf("{term: facing, prefer: bouts}") == keyOf("{term: facing, prefer: bouts, stance: 1}"));
    // Stance k of n: n behaviours, each holding its stance with its own facing term.
    auto stanceKey = [&](int k, int n) {
      std::string behaviors;
      for (int i = 0; i < n; ++i)
        behaviors += fmt::format(
            "  s{0}:\n    stance: {0}\n    discretizer: {{type: polar2d}}\n    reward: {{type: terms, terms: "
            "[{{term: facing, prefer: stance, stance: {0}, stances: {1}}}]}}\n    learner: {{type: value_iteration}}\n",
            i, n);
      return build(behaviors).at(static_cast<std::size_t>(k)).key;
    };
    const std::string stance0 = stanceKey(0, 1);
    CHECK(stance0 != stanceKey(0, 2));
    CHECK(stanceKey(0, 2) != stanceKey(1, 2));
    CHECK(stance0 != keyOf("{term: facing}"));
  }
  SECTION("a learned opponent's against: previous keeps the key self-play rounds had before the choice") {
    auto keyOf = [&](const std::string& environment) {
      const Scenario scenario = parse(approachInserting(19, "    environment: " + environment));
      return behaviorConfigAndKey(scenario.behaviors.front(), app::plugins(), kGraphKey).second;
    };
    const std::string rounds = "{type: learned_opponent, rounds: 3";
    CHECK(keyOf(rounds + "}") == keyOf(rounds + ", against: previous}"));
    CHECK(keyOf(rounds + "}") != keyOf(rounds + ", against: average}"));
  }
  SECTION("a moving_target that does not turn keeps the key it had before turning targets") {
    auto keyOf = [&](const std::string& environment) {
      return build(approachInserting(19, "    environment: " + environment)).front().key;
    };
    CHECK(keyOf("{type: moving_target}") == keyOf("{type: moving_target, max_turn_deg_s: 0, turns: 7}"));
    CHECK(keyOf("{type: moving_target}") != keyOf("{type: moving_target, max_turn_deg_s: 90}"));
    CHECK(keyOf("{type: moving_target, max_turn_deg_s: 90}") !=
          keyOf("{type: moving_target, max_turn_deg_s: 90, turns: 5}"));
  }
  SECTION("a facing term that learns from the real bouts keys on their samples") {
    const Scenario s = parse(
        "  keep:\n    discretizer: {type: polar2d}\n    reward: {type: terms, terms: [{term: facing, prefer: bouts}]}\n"
        "    learner: {type: value_iteration}\n");  // records test::mocap() as the data folder
    const std::string real = buildBehaviors(s, app::plugins(), model(), kGraphKey).front().key;
    CHECK(buildBehaviors(s, app::plugins(), model(), kGraphKey).front().key == real);
    // Another data folder whose only SNU bout is two stick figures facing each other.
    const test::TempDir other("facing_bouts_key");
    const std::filesystem::path motion = other.path / "snu_martial_arts" / "motion";
    std::filesystem::create_directories(motion);
    for (const char* fighter : {"1", "2"})
      std::filesystem::copy_file(test::testData() / "stats" / "stand" / (std::string("fighter_") + fighter + ".bvh"),
                                 motion / (std::string("s_001_1_") + fighter + ".bvh"));
    recordScenarioDataDirectory(other.path);
    std::string made;
    try {
      made = buildBehaviors(s, app::plugins(), model(), kGraphKey).front().key;
    } catch (...) {
      recordScenarioDataDirectory({});
      throw;
    }
    recordScenarioDataDirectory({});
    CHECK(made != real);
    // A data folder without the SNU capture: one error at the term's key, saying where it
    // looked.
    const test::TempDir none("facing_bouts_key_none");
    recordScenarioDataDirectory(none.path);
    try {
      buildBehaviors(s, app::plugins(), model(), kGraphKey);
      recordScenarioDataDirectory({});
      FAIL("expected a ConfigError");
    } catch (const ConfigError& e) {
      recordScenarioDataDirectory({});
      CHECK_THAT(e.what(), Contains("behaviors.keep.reward.terms[0].prefer: bouts: expected the SNU sparring capture "
                                    "s_TTT_K_P.bvh in") &&
                               Contains(none.path.string()));
    }
  }
  SECTION("a parameter given at its default is the same as one left out") {
    CHECK(keyWith("behaviors.approach.learner.alpha_final=0") == base);
    CHECK(keyWith("behaviors.approach.discretizer.min_radius=0") == base);
    // The implicit environment is static_target with its defaults.
    const std::string explicitEnvironment = approachInserting(19, "    environment: {type: static_target}") + kHit;
    CHECK(named(build(explicitEnvironment), "approach").key == base);
  }
}

TEST_CASE("mgrl list names every plugin and parameter with its default and unit", "[behaviors]") {
  const Plugins& plugins = app::plugins();
  const std::string text = app::listText(plugins);
  // The line of `text` that starts with `start` (after any indent), or "".
  auto line = [&](const std::string& start, std::size_t from) {
    std::istringstream in(text.substr(from));
    for (std::string l; std::getline(in, l);) {
      const std::size_t first = l.find_first_not_of(' ');
      if (first != std::string::npos && l.compare(first, start.size(), start) == 0) return l;
    }
    return std::string();
  };
  auto check = [&](const auto& registry, const std::string& heading) {
    const std::size_t section = text.find(heading);
    REQUIRE(section != std::string::npos);
    for (const auto& entry : registry.entries()) {
      CAPTURE(entry.name);
      const std::size_t at = text.find("  " + entry.name + ": ", section);
      REQUIRE(at != std::string::npos);
      for (const ParamSpec& spec : entry.params) {
        CAPTURE(spec.name);
        const std::string l = line(spec.name + " ", at);
        REQUIRE(!l.empty());
        CHECK_THAT(l, Contains("default " + spec.defaultText() + " "));
        if (!spec.unit.empty()) CHECK_THAT(l, Contains(" " + spec.unit + ":"));
        CHECK_THAT(l, Contains(spec.help));
      }
    }
  };
  check(plugins.discretizers, "discretizers (");
  check(plugins.rewards, "rewards (");
  check(plugins.environments, "environment models (");
  check(plugins.learners, "learners (");
  for (const char* name :
       {"polar2d", "cylindrical3d", "approach", "hit", "static_target", "q_learning", "value_iteration"})
    CHECK_THAT(text, Contains(std::string("  ") + name + ": "));
  // Spot checks against the values the scenarios rely on.
  CHECK_THAT(line("rings ", text.find("  polar2d: ")), Contains("default 5") && Contains("vertices"));
  CHECK_THAT(line("sigma ", text.find("  approach: ")), Contains("default 0.1") && Contains(" m:"));
  CHECK_THAT(line("budget ", text.find("  q_learning: ")), Contains("default 10000000") && Contains("actions"));
  CHECK_THAT(text, Contains("static_target: ") && Contains("(no parameters)"));

  // The JSON form says the same, seam by seam.
  const nlohmann::json json = app::listJson(plugins);
  auto checkJson = [&](const auto& registry, const char* seam) {
    CAPTURE(seam);
    const nlohmann::json& list = json[seam];
    REQUIRE(list.is_array());
    REQUIRE(list.size() == registry.entries().size());
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto& entry = registry.entries()[i];
      CHECK(list[i]["name"] == entry.name);
      REQUIRE(list[i]["parameters"].size() == entry.params.size());
      for (std::size_t k = 0; k < entry.params.size(); ++k) {
        CHECK(list[i]["parameters"][k]["name"] == entry.params[k].name);
        CHECK(list[i]["parameters"][k]["default"] == entry.params[k].defaultText());
        CHECK(list[i]["parameters"][k]["unit"] == entry.params[k].unit);
      }
    }
  };
  checkJson(plugins.discretizers, "discretizers");
  checkJson(plugins.rewards, "rewards");
  checkJson(plugins.environments, "environments");
  checkJson(plugins.learners, "learners");
}

// Body points (scenarios/README.md): a distance or effort term, or a success condition, may
// name a skeleton role or a joint; the model built from the capture records the joints, and
// one it lacks is refused where it is written, with the roles and joints there are.
TEST_CASE("a body point names a skeleton role or joint, one the skeleton lacks lists those it has",
          "[behaviors][terms]") {
  auto keeper = [](const std::string& terms, const std::string& success = "") {
    return "  keep:\n"                                  // 6
           "    discretizer: {type: polar2d}\n"          // 7
           "    reward:\n"                               // 8
           "      type: terms\n"                         // 9
           "      terms:\n"                              // 10
           "        - " + terms + "\n" +                 // 11
           "    learner: {type: value_iteration}\n" +    // 12
           (success.empty() ? "" : "    success: " + success + "\n");  // 13
  };
  auto reward = [&](const std::string& terms, std::size_t a, const Eigen::Vector3d& e) {
    return build(keeper(terms)).front().reward->evaluate(model(), a, e);
  };
  const Eigen::Vector3d e(0.3, 0.9, 1.5);
  SECTION("a role and the joint it names give the same reward; the pelvis role is the pelvis's ground point") {
    const double byRole = reward("{term: distance, point: left_fist, d0: 0.5, dims: 3}", 0, e);
    CHECK(byRole > 0);
    CHECK(byRole == reward("{term: distance, point: LeftHand, d0: 0.5, dims: 3}", 0, e));
    CHECK(byRole != reward("{term: distance, point: centroid, d0: 0.5, dims: 3}", 0, e));
    for (std::size_t a = 0; a < model().actionCount(); ++a)
      CHECK(reward("{term: distance, point: Hips, d0: 1}", a, e) ==
            Approx(reward("{term: distance, point: pelvis, d0: 1}", a, e)).epsilon(1e-6));
  }
  SECTION("the hand's distance follows the avatar: 0.5 m ahead of the pelvis at every frame") {
    // Action 1 moves 0.6 m straight ahead in 6 frames; gamma 1 and combine max give the
    // best frame's signal: the hand reaches a target 1.1 m ahead (0.5 + 0.6) at the last.
    const Eigen::Vector3d ahead(0.1, 1.3, 1.1);
    CHECK(build(keeper("{term: distance, point: LeftHand, dims: 3, sigma: 0.01}"), {"behaviors.keep.reward.gamma=1"})
              .front()
              .reward->evaluate(model(), 1, ahead) == Approx(1.0));
  }
  SECTION("effort measures a joint's speed in the capture, or the whole body's") {
    CHECK(reward("{term: effort, point: LeftHand, speed_mps: 1}", 0, e) == Approx(0.97 * std::exp(-2.0)));
    CHECK(reward("{term: effort, point: body, speed_mps: 1}", 0, e) == Approx(0.97 * std::exp(-1.0)));
    CHECK(reward("{term: effort, point: Hips, speed_mps: 1}", 0, e) == Approx(0.97));
  }
  SECTION("a joint the skeleton lacks") {
    const std::string lacks =
        "behaviors.keep.reward.terms[0].point: expected centroid, pelvis, a role (left_fist, right_fist, left_wrist, "
        "right_wrist, left_forearm, right_forearm, left_shoulder, right_shoulder, left_ankle, right_ankle, "
        "left_toe, right_toe, head) or a joint of this skeleton (Hips, LeftHand), found 'LeftHnd'";
    REQUIRE_CONFIG_ERROR(build(keeper("{term: distance, point: LeftHnd, d0: 0.5}")), at(11, 35, lacks));
    REQUIRE_CONFIG_ERROR(build(keeper("{term: effort, point: LeftHnd}")), at(11, 33, lacks));
    CHECK_THROWS_WITH(build(keeper("{term: distance, point: pelvis}", "{term: distance, point: Head, within: 0.1}")),
                      StartsWith(at(13, 38, "behaviors.keep.success.point: expected centroid, pelvis, a role (")) &&
                          Contains("found 'Head'"));
  }
  SECTION("a model that records no joints (made by hand) refuses joints and body") {
    StateActionModel bare = model();
    bare.jointNames.clear();
    bare.roleJoint.clear();
    bare.sourceJoint.clear();
    bare.sourceJointSpeed.clear();
    auto buildOn = [&](const std::string& terms) { return buildBehaviors(parse(keeper(terms)), app::plugins(), bare, kGraphKey); };
    CHECK_THROWS_WITH(buildOn("{term: effort, point: body}"),
                      EndsWith("terms[0].point: no joints for body: this model records no skeleton joints"));
    CHECK_THROWS_WITH(buildOn("{term: distance, point: head}"),
                      EndsWith("terms[0].point: no joint 'head': this model records no skeleton joints"));
    CHECK_NOTHROW(buildOn("{term: distance, point: pelvis}"));
  }
  SECTION("names that are not body points of the term") {
    CHECK_THROWS_WITH(build(keeper("{term: distance, point: body}")),
                      Contains("terms[0].point: expected centroid, pelvis, a role or a joint, found body"));
    CHECK_THROWS_WITH(build(keeper("{term: effort, point: centroid}")),
                      Contains("terms[0].point: expected pelvis (root speed), body"));
    CHECK_THROWS_WITH(build(keeper("{term: distance, point: 'Left Hand'}")),
                      Contains("terms[0].point: expected one of: centroid, pelvis, or a skeleton role or joint (up to "
                               "200 printable characters, no spaces), found 'Left Hand'"));
  }
}

TEST_CASE("a reward term the caller registers in Plugins is read, checked, listed and paid by the terms reward",
          "[behaviors][plugins]") {
  // A term that pays a constant: s_k(t) = level at every frame.
  class Constant final : public Term {
   public:
    explicit Constant(double level) : level_(level) {}
    double signal(const TermFrame&) const override { return level_; }

   private:
    double level_;
  };
  Plugins plugins;
  registerBuiltins(plugins);
  plugins.terms.add({"constant",
                     "a constant level",
                     {ParamSpec::number("level", 0.5, 0, 1, "", "the signal at every frame"),
                      ParamSpec::number("weight", 1, 0, 1000, "", "w_k")},
                     [](const Params& p) { return std::make_unique<Constant>(p.number("level")); }});
  const char* block = "{type: terms, gamma: 0.9, terms: [{term: constant, level: 0.25, weight: 2}]}";
  const std::unique_ptr<Reward> reward = plugins.rewards.create(ConfigNode::parse(block, "r"));
  reward->bind(model());
  // max over t of gamma^t w s: the first frame's, 0.9 * 2 * 0.25.
  CHECK(reward->evaluate(model(), 0, TargetState(Eigen::Vector3d(1, 0, 0))) == Approx(0.45));
  CHECK(reward->terms()[0]["term"] == "constant");
  // Its parameters are checked like a built-in term's, and the built-in plug-ins do not know it.
  REQUIRE_THROWS_WITH(
      plugins.rewards.create(ConfigNode::parse("{type: terms, terms: [{term: constant, level: 2}]}", "r")),
      Contains("level") && Contains("found 2"));
  REQUIRE_THROWS_WITH(app::plugins().rewards.create(ConfigNode::parse(block, "r")),
                      Contains("unknown term 'constant'") && Contains("distance, facing"));
  CHECK_THAT(app::listText(plugins), Contains("  term: constant  a constant level\n"));
  CHECK_THAT(app::listText(app::plugins()), !Contains("term: constant"));
  CHECK(app::listJson(plugins)["reward_terms"].back()["name"] == "constant");
}

}  // namespace behavior_config_test
