// The session stage (framework/session/): one way into the pipeline for every
// command, the viewer, the benchmarks and Python. A session opens the scenario, its graph,
// behaviours, the task they share and the policy bundle; controllers are listed, checked
// and made in one place; hits become JSON in one place.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <map>
#include <span>
#include <stdexcept>

#include <fmt/format.h>

#include "app/learn_commands.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/session/episodes.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/simulate.hpp"
#include "mgrl/session/trials.hpp"
#include "test_support.hpp"

namespace mgrl::session_test {
namespace {

namespace fs = std::filesystem;
using Catch::Contains;

const fs::path kBoxing = fs::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing.yaml";
const fs::path kKick = fs::path(MGRL_SOURCE_DIR) / "scenarios" / "kick.yaml";

// Boxing trained by value iteration: the same shared folder, made the same way, as
// world_test's fixture (test::sharedResult trains it once for the whole suite).
fs::path trainedBoxing() {
  return test::sharedResult("boxing-value-iteration", [](const fs::path& d) {
    app::TrainOptions train;
    train.scenario = kBoxing;
    train.dataDir = test::mocap();
    train.cacheDir = d;
    train.out = d / "policy";
    train.sets = {"behaviors.approach.learner.type=value_iteration", "behaviors.hit.learner.type=value_iteration"};
    app::runTrain(train);
  });
}

SessionOptions boxingOptions(const fs::path& cache) {
  SessionOptions options;
  options.plugins = &builtinPlugins();
  options.scenario = kBoxing;
  options.dataDir = test::mocap();
  options.cacheDir = cache;
  options.sets = {"behaviors.approach.learner.type=value_iteration", "behaviors.hit.learner.type=value_iteration"};
  return options;
}

}  // namespace

TEST_CASE("a session opens the scenario's graph, behaviours, task and policy bundle together", "[session][data]") {
  const fs::path trained = trainedBoxing();
  const auto session = openSession(boxingOptions(trained), {.policy = PolicyNeed::Required, .policyDir = trained / "policy"});
  REQUIRE(session->behaviors.size() == 2);
  CHECK(session->behaviors[0].name == "approach");
  CHECK(session->model().stateCount() > 0);
  CHECK(session->graph.db.skeleton);  // the capture is parsed by default: poses need it
  // One policy part and one search part per behaviour, each pointing at the behaviour's own
  // grid and reward; the tables have a row per (state, vertex).
  REQUIRE(session->policy.size() == 2);
  REQUIRE(session->search.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(session->search[i].reward == session->behaviors[i].reward.get());
    CHECK(session->policy[i].table->vertexCount() == session->policy[i].grid->vertexCount());
    CHECK(session->policy[i].weight == session->behaviors[i].weight);
  }
  CHECK(session->policyDir == trained / "policy");
  CHECK(session->policyNote.empty());
  // The task: boxing.yaml's gamma (0.97 in both behaviours), a static target, and its world
  // section as read once (mode sparring, no target height given).
  CHECK(session->task.gamma == Approx(0.97));
  CHECK(session->task.environment == session->behaviors[0].environment.get());
  CHECK(session->task.environment->type() == "static_target");
  CHECK_FALSE(session->task.opponent);
  CHECK(session->task.world.mode == "sparring");
  CHECK(std::isnan(session->task.targetHeight(std::nan(""))));
  CHECK(session->task.targetHeight(1.2) == 1.2);
  CHECK_FALSE(session->body.points.empty());
}

TEST_CASE(
    "a self-play round's tables are played only when every behaviour has one, as a value: the session keeps its "
    "own, and simulate asks for the bundle's",
    "[session][data]") {
  const fs::path trained = trainedBoxing();
  const auto bare = openSession(boxingOptions(trained), {.motion = false});
  CHECK_THROWS_WITH(bare->roundPolicies(1), "self-play round 1: expected a policy bundle, found none");

  // Bundles with round 1 of approach only, and of both behaviours (approach's changed).
  test::TempDir temp("session-rounds");
  const auto opened =
      openSession(boxingOptions(trained), {.policy = PolicyNeed::Required, .policyDir = trained / "policy"});
  PolicyBundle rounds = loadPolicyBundle(trained / "policy", opened->model(), opened->graph.key);
  const QTable approach = rounds.behaviors.at("approach").table, hit = rounds.behaviors.at("hit").table;
  rounds.behaviors["approach-round1"] = rounds.behaviors.at("approach");
  rounds.behaviors["approach-round1"].table.at(0, 0) += 1;
  savePolicyBundle(temp.path / "partial", rounds);
  rounds.behaviors["hit-round1"] = rounds.behaviors.at("hit");
  savePolicyBundle(temp.path / "full", rounds);

  const auto partial =
      openSession(boxingOptions(trained), {.policy = PolicyNeed::Required, .policyDir = temp.path / "partial"});
  CHECK_THROWS_WITH(partial->roundPolicies(1), Contains("expected self-play round 1's table for behaviour 'hit' "
                                                        "(hit-round1), found only approach, approach-round1, hit"));

  const auto session =
      openSession(boxingOptions(trained), {.policy = PolicyNeed::Required, .policyDir = temp.path / "full"});
  const Policies played = session->roundPolicies(1);
  REQUIRE(played.main.size() == 2);
  REQUIRE(played.mainBundle);
  CHECK(played.main[0].table->at(0, 0) == approach.at(0, 0) + 1);
  CHECK(*played.main[1].table == hit);
  CHECK(played.main[0].table == &played.mainBundle->behaviors.at("approach").table);
  CHECK(played.mainBundle->behaviors.count("approach-round1") == 0);
  CHECK(played.dir == temp.path / "full");
  // The session still plays its final tables.
  CHECK(session->policy[0].table == &session->bundle.behaviors.at("approach").table);
  CHECK(*session->policy[0].table == approach);
  CHECK(session->bundle.behaviors.count("approach-round1") == 1);

  // simulate's round is the bundle's: with tables of the caller's own it is refused.
  SimulateSettings settings;
  settings.round = 1;
  Outputs outputs;
  CHECK_THROWS_WITH(simulate(*session, settings, outputs, &session->policy),
                    "--round: expected the bundle's tables, found tables given by the caller");
}

TEST_CASE("a session without the capture's poses starts from the cached model alone, and simulate asks for them",
          "[session][data]") {
  const fs::path trained = trainedBoxing();
  const auto session = openSession(boxingOptions(trained), {.motion = false});
  CHECK(session->policy.empty());
  CHECK(session->policyDir.empty());
  CHECK(session->graph.fromCache);
  CHECK_FALSE(session->hasMotion());  // nothing parsed: the graph came from the cache
  CHECK(session->body.points.empty());
  SimulateSettings settings;
  settings.controller = {"random"};
  Outputs outputs;
  CHECK_THROWS_WITH(simulate(*session, settings, outputs),
                    Contains("simulate: expected a session opened with the capture"));

  const auto captured = openSession(boxingOptions(trained));
  REQUIRE(captured->hasMotion());
  CHECK(captured->graph.db.frameCount() == captured->graph.model.framesTotal);
  CHECK_FALSE(captured->body.points.empty());
  settings.seconds = 1;
  settings.avatars = 2;
  CHECK(simulate(*captured, settings, outputs)["frames"].get<std::size_t>() > 0);
}

TEST_CASE("a session refuses a missing bundle when one is required, and says why when it is optional",
          "[session][data]") {
  test::TempDir temp("session-no-bundle");
  const SessionOptions options = boxingOptions(temp.path);
  CHECK_THROWS_WITH(openSession(options, {.policy = PolicyNeed::Required}),
                    Contains("no policy bundle here: run `mgrl train") && Contains("boxing.yaml"));
  // The refusal comes before the graph: nothing was built into the cache.
  CHECK_FALSE(fs::exists(temp.path / "graphs"));
  const auto session = openSession(options, {.policy = PolicyNeed::IfAvailable, .motion = false});
  CHECK(session->policy.empty());
  CHECK_THAT(session->policyNote, Contains("no policy bundle here"));
}

TEST_CASE("a session calls the caller's checks after the scenario's and before the graph", "[session][data]") {
  test::TempDir temp("session-before-graph");
  SessionNeeds needs;
  needs.motion = false;
  bool called = false;
  needs.beforeGraph = [&](const Scenario& scenario) {
    called = true;
    CHECK(scenario.name == "boxing");
    CHECK_FALSE(fs::exists(temp.path / "graphs"));
    throw Error("--bvh-out: the caller's own refusal");
  };
  CHECK_THROWS_WITH(openSession(boxingOptions(temp.path), needs), "--bvh-out: the caller's own refusal");
  CHECK(called);
  CHECK_FALSE(fs::exists(temp.path / "graphs"));
}

TEST_CASE("a scenario whose behaviours disagree on the world they share is refused at the behaviour",
          "[session][data]") {
  test::TempDir temp("session-disagree");
  SessionOptions options = boxingOptions(temp.path);
  options.sets.push_back("behaviors.hit.reward.gamma=0.9");
  CHECK_THROWS_WITH(openSession(options, {.motion = false}),
                    Contains("behaviors.hit.reward.gamma") &&
                        Contains("expected gamma 0.97 as behaviors.approach.reward has") && Contains("found 0.9"));
  options = boxingOptions(temp.path);
  options.sets.push_back("behaviors.hit.environment.type=moving_target");
  CHECK_THROWS_WITH(openSession(options, {.motion = false}),
                    Contains("behaviors.hit.environment") &&
                        Contains("expected the environment model of behaviors.approach") &&
                        Contains("share one world") && Contains("moving_target"));
  // Without a scenario file (tests, Python), the same check names the source.
  const auto session = openSession(boxingOptions(temp.path), {.motion = false});
  CHECK_NOTHROW(makeTask(session->behaviors, "built.yaml"));
  CHECK_THROWS_WITH(makeTask(std::vector<Behavior>{}, "built.yaml"), "built.yaml: expected at least one behaviour, found none");
}

TEST_CASE("episodes start where reset places them and draw the rest as unplaced ones do", "[session][data]") {
  test::TempDir temp("session-episodes");
  const auto session = openSession(boxingOptions(temp.path), {.motion = false});
  const std::int64_t states = static_cast<std::int64_t>(session->model().stateCount());
  REQUIRE(session->behaviors[1].name == "hit");  // a static target
  Episodes episodes(session->model(), session->behaviors[1], 1, {});
  episodes.reset(0, 7);
  const std::uint32_t drawnState = episodes.state(0);
  const Eigen::Vector3d drawnTarget = episodes.target(0).position;
  const std::int64_t placedState = (drawnState + 1) % states;
  const Eigen::Vector3d placedTarget(0.1, 1.2, 0.5);
  // The same seed draws the same numbers, placed or not: what is not placed is as drawn.
  episodes.reset(0, 7, {.state = placedState});
  CHECK(episodes.state(0) == placedState);
  CHECK(episodes.target(0).position == drawnTarget);
  episodes.reset(0, 7, {.target = placedTarget});
  CHECK(episodes.state(0) == drawnState);
  CHECK(episodes.target(0).position == placedTarget);
  CHECK_FALSE(episodes.target(0).moving());
  // A bad placement is refused before the slot changes.
  CHECK_THROWS_WITH(episodes.reset(0, 8, {.state = states}),
                    fmt::format("options['state']: expected a graph state in [0, {}), found {}", states, states));
  CHECK_THROWS_WITH(episodes.reset(0, 8, {.state = -1}), Contains("found -1"));
  CHECK_THROWS_WITH(episodes.reset(0, 8, {.state = 0, .target = Eigen::Vector3d(NAN, 0, 1)}),
                    "options['target']: expected a finite position (x, y, z in metres, the avatar's frame), found "
                    "(nan, 0, 1)");
  CHECK(episodes.state(0) == drawnState);
  CHECK(episodes.target(0).position == placedTarget);
}

TEST_CASE("mgrl train refuses behaviours that disagree on their world before training anything", "[session][data]") {
  test::TempDir temp("session-train-disagree");
  app::TrainOptions train;
  static_cast<SessionOptions&>(train) = boxingOptions(temp.path);
  train.sets.push_back("behaviors.hit.reward.gamma=0.9");
  train.out = temp.path / "policy";
  CHECK_THROWS_WITH(app::runTrain(train), Contains("behaviors.hit.reward.gamma") && Contains("expected gamma 0.97"));
  CHECK_FALSE(fs::exists(train.out));
}

TEST_CASE("a scenario's world section reaches the task: kick's target height", "[session][data]") {
  test::TempDir temp("session-kick");
  SessionOptions options;
  options.plugins = &builtinPlugins();
  options.scenario = kKick;
  options.dataDir = test::mocap();
  options.cacheDir = temp.path;
  const auto session = openSession(options, {.motion = false});
  CHECK(session->task.world.targetHeight == Approx(0.6));
  CHECK(session->task.targetHeight(std::nan("")) == Approx(0.6));
  CHECK(session->task.targetHeight(1.0) == 1.0);
}

TEST_CASE("the controllers are listed, checked and made in one place", "[session][controllers]") {
  const ControllerRegistry& controllers = builtinPlugins().controllers;
  REQUIRE(controllers.entries().size() == 3);
  CHECK(controllers.entries()[0].name == "policy");
  CHECK(controllers.entries()[0].needsPolicy);
  CHECK(controllers.find("online_search")->searches);
  CHECK(controllers.find("sarsa") == nullptr);
  CHECK(controllerAlternatives(controllers) == "policy, online_search or random");
  CHECK(controllerAlternatives(controllers, true) == "online_search or random");
  ControllerRegistry more = controllers;
  CHECK_THROWS_AS(more.add({.name = "random", .summary = "another", .make = nullptr}),
                  std::logic_error);  // a name is registered once
  CHECK_NOTHROW(checkControllerChoice(controllers, {"random", 3, 0}));
  CHECK_THROWS_WITH(checkControllerChoice(controllers, {"sarsa", 3, 0}),
                    "--controller: expected one of: policy, online_search, random, found 'sarsa'");
  CHECK_THROWS_WITH(checkControllerChoice(controllers, {"online_search", 9, 0}),
                    "--horizon: expected a search depth in actions in [1, 8], found 9");
  CHECK_THROWS_WITH(checkControllerChoice(controllers, {"online_search", 0, 0}),
                    "--horizon: expected a search depth in actions in [1, 8], found 0");
  CHECK_THROWS_WITH(checkControllerChoice(controllers, {"online_search", 3, 6.5}),
                    "--horizon-seconds: expected seconds of motion to search in [0, 5], found 6.5");
  CHECK_THROWS_WITH(checkControllerChoice(controllers, {"online_search", 3, std::nan("")}),
                    Contains("--horizon-seconds: expected seconds of motion to search in [0, 5], found nan"));
  // Named as the caller names them (the viewer's protocol has its own field names).
  CHECK_THROWS_WITH(checkControllerChoice(controllers, {"x", 3, 0}, {.controller = "controller.controller"}),
                    Contains("controller.controller: expected one of"));
}

namespace {

// A controller the framework does not know: the first allowed out-action, every decision
// counted.
class FirstActionController final : public Controller {
 public:
  FirstActionController(const StateActionModel& model, std::atomic<std::size_t>& decisions)
      : model_(model), decisions_(decisions) {}
  std::size_t choose(std::uint32_t s, const TargetState&, Rng&) override {
    ++decisions_;
    return model_.stateActionBegin[s];
  }
  std::size_t choose(std::uint32_t s, const TargetState&, Rng&, std::span<const std::uint8_t> allowed) override {
    ++decisions_;
    const auto j = static_cast<std::size_t>(std::find(allowed.begin(), allowed.end(), 1) - allowed.begin());
    if (j == allowed.size()) throw std::logic_error("first_action: expected an allowed action, found none");
    return model_.stateActionBegin[s] + j;
  }

 private:
  const StateActionModel& model_;
  std::atomic<std::size_t>& decisions_;
};

}  // namespace

TEST_CASE("a controller the caller registers is chosen by name and runs in the session's world",
          "[session][controllers][data]") {
  std::atomic<std::size_t> decisions{0};
  Plugins plugins;  // the built-in registries, and two controllers more
  registerBuiltins(plugins);
  plugins.controllers.add(
      {.name = "first_action",
       .summary = "the first allowed out-action",
       .make = [&decisions](const ControllerChoice&, const ControllerParts& parts) -> std::unique_ptr<Controller> {
         return std::make_unique<FirstActionController>(*parts.model, decisions);
       }});
  plugins.controllers.add(
      {.name = "own_policy",
       .summary = "needs the trained tables",
       .needsPolicy = true,
       .make = [](const ControllerChoice&, const ControllerParts& parts) -> std::unique_ptr<Controller> {
         return std::make_unique<RandomController>(*parts.model);
       }});
  test::TempDir temp("session-own-controller");
  SessionOptions options = boxingOptions(temp.path);
  options.plugins = &plugins;
  const auto session = openSession(options);

  World world(session->worldSetup(2, 1, {.name = "first_action"}));
  world.run(300);
  CHECK(decisions > 0);
  CHECK(controllerAlternatives(session->plugins().controllers) ==
        "policy, online_search, random, first_action or own_policy");
  // What an entry says it needs is asked for when the world is set up (no bundle here).
  CHECK_THROWS_WITH(
      session->worldSetup(2, 1, {.name = "own_policy"}),
      "--controller own_policy: expected a trained policy bundle, found none (train one with mgrl train)");
  // An unknown name: the message lists the session's controllers, as it lists the built-in ones.
  CHECK_THROWS_WITH(session->worldSetup(2, 1, {.name = "sarsa"}),
                    "--controller: expected one of: policy, online_search, random, first_action, own_policy, found "
                    "'sarsa'");
  CHECK_THROWS_WITH(checkControllerChoice(builtinPlugins().controllers, {.name = "first_action"}),
                    "--controller: expected one of: policy, online_search, random, found 'first_action'");
}

TEST_CASE("a session makes every listed controller, and a world that repeats itself", "[session][data]") {
  const fs::path trained = trainedBoxing();
  const auto session = openSession(boxingOptions(trained), {.policy = PolicyNeed::Required, .policyDir = trained / "policy"});
  const StateActionModel& model = session->model();
  Rng rng(3);
  const ControllerRegistry& controllers = session->plugins().controllers;
  for (const ControllerRegistry::Entry& entry : controllers.entries()) {
    INFO(entry.name);
    const std::unique_ptr<Controller> c = makeController(controllers, {entry.name, 2, 0}, session->controllerParts());
    REQUIRE(c);
    const std::size_t a = c->choose(0, TargetState(0.5, 1.2, 0.4), rng);
    CHECK(a >= model.stateActionBegin[0]);
    CHECK(a < model.stateActionBegin[1]);
  }
  // A policy without tables is refused when it is made, not at the first decision.
  ControllerParts noTables = session->controllerParts();
  noTables.policy.clear();
  CHECK_THROWS_WITH(makeController(controllers, {"policy", 3, 0}, noTables),
                    Contains("expected a trained policy bundle"));

  // The session's world: its scenario's world section, its task (no opponent), its body;
  // the same seed gives the same hits.
  auto run = [&](const std::string& controller) {
    WorldSetup setup = session->worldSetup(4, 5, {controller, 2, 0});
    CHECK(setup.params.mode == "sparring");
    CHECK(setup.body == &session->body);
    CHECK_FALSE(setup.opponent);
    World world(setup);
    world.run(600);
    return world.events();
  };
  const std::vector<HitEvent> first = run("policy");
  CHECK_FALSE(first.empty());  // trained sparring partners land punches in 20 s
  const std::vector<HitEvent> again = run("policy");
  REQUIRE(first.size() == again.size());
  for (std::size_t i = 0; i < first.size(); ++i) CHECK(hitEventJson(first[i]) == hitEventJson(again[i]));
  CHECK_THROWS_WITH(session->worldSetup(2, 1, {"sarsa", 3, 0}), Contains("--controller: expected one of"));
}

TEST_CASE("a hit reads the same in the events file and the viewer's protocol", "[session]") {
  HitEvent e;
  e.time = 1.5;
  e.attacker = 3;
  e.target = 2;
  e.hand = 1;
  e.part = BodyPart::Chest;
  e.speed = 4.25;
  e.point = Eigen::Vector3d(0.1, 1.3, -0.2);
  const nlohmann::json j = hitEventJson(e);
  CHECK(
      j.dump() ==
      R"({"attacker":3,"blocked":false,"hand":"right","limb":"fist","part":"chest","point":[0.1,1.3,-0.2],"speed":4.25,"target":2,"time":1.5})");
  e.blocked = true;  // met the partner's left forearm
  e.part = BodyPart::LeftArm;
  CHECK(hitEventJson(e)["part"] == "left_arm");
  CHECK(hitEventJson(e)["blocked"] == true);
  e.blocked = false;
  e.target = -1;  // the attacker's own target
  e.kick = true;
  e.hand = 0;
  CHECK(hitEventJson(e)["part"] == "target");
  CHECK(hitEventJson(e)["limb"] == "foot");
  CHECK(hitEventJson(e)["hand"] == "left");
}

// boxing_spar's stances. The session's world holds them, and eval's trial i holds
// stance i mod 3 through every decision of the trial.
TEST_CASE("a scenario's stances reach the world and eval's trials: trial i holds stance i mod N", "[session][data]") {
  const test::TempDir cache("session-stances");
  SessionOptions options;
  options.plugins = &builtinPlugins();
  options.scenario = fs::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing_spar.yaml";
  options.dataDir = test::mocap();
  options.cacheDir = cache.path;
  const auto session = openSession(options, {.motion = false});
  REQUIRE(session->behaviors.size() == 3);
  for (int k = 0; k < 3; ++k) CHECK(session->behaviors[static_cast<std::size_t>(k)].stance == k);
  CHECK(session->worldSetup(2, 1, {"random"}).stances == 3);
  const Trials trials(session->model(), session->behaviors, session->task, std::nan(""), "boxing_spar",
                      session->plugins().conditions);
  std::vector<std::int32_t> seen;
  const ChooseAction record = [&](std::uint32_t s, const TargetState& e) -> std::size_t {
    seen.push_back(e.stance);
    return session->model().stateActionBegin[s];
  };
  // Trials shorter than any action: one decision each.
  trials.run(record, 7, 0.01, 3);
  CHECK(seen == std::vector<std::int32_t>{0, 1, 2, 0, 1, 2, 0});
  // Longer trials: every decision of trial i in stance i mod 3 (the environment's next
  // target keeps it).
  seen.clear();
  trials.run(record, 3, 4, 3);
  REQUIRE(seen.size() > 6);
  CHECK(std::is_sorted(seen.begin(), seen.end()));
  CHECK(seen.front() == 0);
  CHECK(seen.back() == 2);
  CHECK(std::count(seen.begin(), seen.end(), 1) > 0);
}

}  // namespace mgrl::session_test
