// The learned opponent: how time is handled when the two fighters' actions end at
// different moments, and that the environment model's transition is exact: replaying both
// fighters frame by frame in world coordinates lands where next() and track() say.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <catch2/catch.hpp>

#include "app/plugins.hpp"
#include "cli_support.hpp"
#include "environments/environments.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/self_play.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/training.hpp"
#include "rewards/term.hpp"
#include "test_support.hpp"

namespace mgrl::learned_opponent_test {

namespace fs = std::filesystem;

namespace {

struct SparFixture {
  Scenario scenario;
  StateActionModel model;
  std::vector<Behavior> behaviors;

  SparFixture()
      : scenario(loadScenario(std::string(test::sourceDirectory()) + "/scenarios/spar_learned.yaml", test::mocap())),
        model(buildStateActionModel(loadMotionDatabase(scenario.motion, {}), scenario.graph)) {
    behaviors = buildBehaviors(scenario, app::plugins(), model, "test");
  }
  const environments::LearnedOpponent& opponent() const {
    return dynamic_cast<const environments::LearnedOpponent&>(*behaviors.front().environment);
  }
};

SparFixture& fixture() {
  static SparFixture f;
  return f;
}

double wrapped(double angle) { return std::remainder(angle, 2 * M_PI); }

// The motion that undoes g: compose(g, inverse(g)) is no motion.
GroundMotion inverse(const GroundMotion& g) {
  const Eigen::Vector3d back = inverseTransformPoint(g, Eigen::Vector3d::Zero());
  return {back.x(), back.z(), -g.dyaw};
}

}  // namespace

TEST_CASE("a learned opponent's state is its end state and phase, one grid layer each", "[opponent][data]") {
  SparFixture& f = fixture();
  const StateActionModel& m = f.model;
  const auto& opponent = f.opponent();
  const Discretizer& grid = *f.behaviors.front().discretizer;
  REQUIRE(opponent.opponentStates() == m.stateCount() * 2);
  REQUIRE(grid.hasOpponentLayers());
  CHECK(grid.layerVertexCount() == 6 * 4 * 6);
  CHECK(grid.vertexCount() == grid.layerVertexCount() * m.stateCount() * 2);
  // A vertex's state carries its layer as the opponent's state; locating it finds that layer
  // exactly (no interpolation across opponent states).
  const std::size_t v = 5 * grid.layerVertexCount() + 17;
  const TargetState e = grid.vertexState(v);
  CHECK(e.opponent == 5);
  GridCell cell;
  REQUIRE(grid.locate(e, cell));
  CHECK(cell.layerFrac == 0);
  const Stencil stencil = grid.stencil(cell);
  CHECK(stencil.size == 8);
  for (int k = 0; k < stencil.size; ++k)
    if (stencil.weight[k] > 0) CHECK(stencil.vertex[k] / grid.layerVertexCount() == 5);
  // Phases: bucket b of an action's frames left, and the frames a bucket stands for.
  CHECK(opponent.phaseOf(1, 10) == 0);
  CHECK(opponent.phaseOf(5, 10) == 0);
  CHECK(opponent.phaseOf(6, 10) == 1);
  CHECK(opponent.phaseOf(10, 10) == 1);
  for (std::uint32_t s = 0; s < m.stateCount(); ++s) {
    const std::uint32_t r = opponent.representative(s);
    CHECK(m.actionTo[r] == s);
    const auto length = static_cast<std::uint32_t>(m.actionLength(r));
    for (std::uint32_t b = 0; b < 2; ++b) {
      const std::uint32_t tau = opponent.framesLeft(m, s, b);
      CHECK(tau >= 1);
      CHECK(tau <= length);
      if (length >= 2) CHECK(opponent.phaseOf(tau, length) == b);
    }
  }
}

TEST_CASE("during one long avatar action the opponent decides several times, each at its own action's end",
          "[opponent][data]") {
  SparFixture& f = fixture();
  const StateActionModel& m = f.model;
  const auto& opponent = f.opponent();
  // The avatar's longest action; the opponent about to arrive at a state whose actions are short.
  std::size_t longest = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a)
    if (m.actionLength(a) > m.actionLength(longest)) longest = a;
  const std::size_t L = m.actionLength(longest);
  REQUIRE(L >= 40);
  TargetState e(Eigen::Vector3d(0.3, 1.4, 1.2), 0.0, M_PI);
  std::size_t bestDecisions = 0;
  for (std::uint32_t s = 0; s < m.stateCount(); ++s) {
    e.opponent = static_cast<std::int32_t>(2 * s);
    std::vector<OpponentFrame> track;
    opponent.track(m, longest, e, track);
    REQUIRE(track.size() == L);
    // The frames it plays are consecutive: within an action offset + 1; at an action's end
    // a new action from its first frame, decided at the root the last one ended at.
    std::size_t decisions = 0;
    for (std::size_t t = 1; t < L; ++t) {
      const OpponentFrame& a = track[t - 1];
      const OpponentFrame& b = track[t];
      if (b.action == a.action && b.offset == a.offset + 1) {
        CHECK(b.decision.dx == a.decision.dx);
        continue;
      }
      ++decisions;
      REQUIRE(a.offset == m.actionLength(a.action));
      REQUIRE(b.offset == 1);
      CHECK(m.actionFrom[b.action] == m.actionTo[a.action]);
      const GroundMotion end = compose(a.decision, m.displacement(a.action));
      CHECK(b.decision.dx == Approx(end.dx).margin(1e-12));
      CHECK(b.decision.dz == Approx(end.dz).margin(1e-12));
      CHECK(wrapped(b.decision.dyaw - end.dyaw) == Approx(0).margin(1e-12));
    }
    bestDecisions = std::max(bestDecisions, decisions);
    // next() ends where the track does: its end state and phase, its root seen from the
    // avatar's end.
    const TargetState n = opponent.next(m, longest, e);
    const OpponentFrame& last = track.back();
    const std::uint32_t left = static_cast<std::uint32_t>(m.actionLength(last.action)) - last.offset;
    const std::uint32_t expectState = left == 0 ? m.actionFrom[last.action] : m.actionTo[last.action];
    if (left > 0) CHECK(static_cast<std::uint32_t>(n.opponent) / 2 == expectState);
    const GroundMotion root = opponentRootAt(m, last);
    const Eigen::Vector3d seen = inverseTransformPoint(m.displacement(longest), Eigen::Vector3d(root.dx, 0, root.dz));
    CHECK(n.position.x() == Approx(seen.x()).margin(1e-12));
    CHECK(n.position.z() == Approx(seen.z()).margin(1e-12));
    CHECK(n.position.y() == e.position.y());
  }
  // A 2.3 s punch against 0.2 s shuffles: the opponent decides several times inside it.
  CHECK(bestDecisions >= 3);
}

TEST_CASE(
    "the learned opponent's transition is deterministic and exact: a frame-by-frame replay of both fighters in "
    "world coordinates lands where the table says",
    "[opponent][data]") {
  SparFixture& f = fixture();
  const StateActionModel& m = f.model;
  const auto& opponent = f.opponent();
  const EnvironmentModel& environment = *f.behaviors.front().environment;
  Rng rng(7);
  std::size_t decisions = 0, frames = 0;
  std::vector<double> snapGap;  // how far the snapped opponent is from one that kept its true action
  for (int episode = 0; episode < 20; ++episode) {
    // World frame: the avatar starts at the origin facing +Z.
    GroundMotion avatar{};
    auto s = static_cast<std::uint32_t>(rng.below(m.stateCount()));
    TargetState e = environment.draw(Eigen::Vector3d(1.5 * rng.uniform() - 0.75, 1.4, 1.0 + rng.uniform()), rng);
    // The opponent in the world: the action it plays, frames played, the root it decided at.
    std::uint32_t os = static_cast<std::uint32_t>(e.opponent) / 2;
    std::uint32_t oa = opponent.representative(os);
    std::uint32_t played = static_cast<std::uint32_t>(m.actionLength(oa)) -
                           opponent.framesLeft(m, os, static_cast<std::uint32_t>(e.opponent) % 2);
    const GroundMotion start = compose(avatar, {e.position.x(), e.position.z(), e.heading});
    GroundMotion odecision = compose(start, inverse(actionFrameMotion(m, oa, played)));
    for (int step = 0; step < 12; ++step) {
      const std::size_t a = m.stateActionBegin[s] + rng.below(m.stateActionBegin[s + 1] - m.stateActionBegin[s]);
      const auto L = static_cast<std::uint32_t>(m.actionLength(a));
      std::vector<OpponentFrame> track;
      opponent.track(m, a, e, track);
      const TargetState predicted = environment.next(m, a, e);
      // Deterministic: the same call gives the same bits.
      const TargetState again = environment.next(m, a, e);
      REQUIRE(std::memcmp(&predicted.position, &again.position, sizeof predicted.position) == 0);
      REQUIRE(predicted.heading == again.heading);
      REQUIRE(predicted.opponent == again.opponent);
      // Frame by frame in the world.
      for (std::uint32_t t = 1; t <= L; ++t) {
        if (played == m.actionLength(oa)) {
          odecision = compose(odecision, m.displacement(oa));
          os = m.actionTo[oa];
          // The opponent decides with the avatar where the world has it at this frame.
          const GroundMotion selfSeen = [&] {
            const Eigen::Vector3d p = inverseTransformPoint(avatar, Eigen::Vector3d(odecision.dx, 0, odecision.dz));
            return GroundMotion{p.x(), p.z(), wrapped(odecision.dyaw - avatar.dyaw)};
          }();
          oa = opponent.choose(m, os, selfSeen, a, t - 1, e.position.y());
          played = 0;
        }
        ++played;
        ++frames;
        // The track's frame, carried into the world, is the replay's.
        const OpponentFrame& o = track[t - 1];
        REQUIRE(o.action == oa);
        REQUIRE(o.offset == played);
        const GroundMotion world = compose(avatar, opponentRootAt(m, o));
        const GroundMotion replay = compose(odecision, actionFrameMotion(m, oa, played));
        CHECK(world.dx == Approx(replay.dx).margin(1e-9));
        CHECK(world.dz == Approx(replay.dz).margin(1e-9));
        CHECK(wrapped(world.dyaw - replay.dyaw) == Approx(0).margin(1e-9));
      }
      if (played == m.actionLength(oa)) {  // it arrives exactly at the avatar's end: decides there
        odecision = compose(odecision, m.displacement(oa));
        os = m.actionTo[oa];
        const Eigen::Vector3d p = inverseTransformPoint(avatar, Eigen::Vector3d(odecision.dx, 0, odecision.dz));
        oa = opponent.choose(m, os, {p.x(), p.z(), wrapped(odecision.dyaw - avatar.dyaw)}, a, L, e.position.y());
        played = 0;
      }
      avatar = compose(avatar, m.displacement(a));
      s = m.actionTo[a];
      ++decisions;
      // At the avatar's decision: the state the table holds is the world's, seen from the avatar.
      const GroundMotion root = compose(odecision, actionFrameMotion(m, oa, played));
      const Eigen::Vector3d seen = inverseTransformPoint(avatar, Eigen::Vector3d(root.dx, e.position.y(), root.dz));
      CHECK(predicted.position.x() == Approx(seen.x()).margin(1e-9));
      CHECK(predicted.position.z() == Approx(seen.z()).margin(1e-9));
      CHECK(wrapped(predicted.heading - (root.dyaw - avatar.dyaw)) == Approx(0).margin(1e-9));
      const auto length = static_cast<std::uint32_t>(m.actionLength(oa));
      CHECK(predicted.opponent ==
            static_cast<std::int32_t>(m.actionTo[oa] * 2 + opponent.phaseOf(length - played, length)));
      // The snap (sample and hold): from here the table takes the opponent to be on its end
      // state's representative action; how far that one's end is from the true action's.
      os = m.actionTo[oa];
      const std::uint32_t r = opponent.representative(os);
      const std::uint32_t rplayed = static_cast<std::uint32_t>(m.actionLength(r)) -
                                    opponent.framesLeft(m, os, static_cast<std::uint32_t>(predicted.opponent) % 2);
      const GroundMotion trueEnd = compose(odecision, m.displacement(oa));
      const GroundMotion snappedDecision = compose(root, inverse(actionFrameMotion(m, r, rplayed)));
      const GroundMotion snappedEnd = compose(snappedDecision, m.displacement(r));
      snapGap.push_back(std::hypot(trueEnd.dx - snappedEnd.dx, trueEnd.dz - snappedEnd.dz));
      oa = r;
      played = rplayed;
      odecision = snappedDecision;
      e = predicted;
    }
  }
  std::sort(snapGap.begin(), snapGap.end());
  WARN(
      fmt::format("learned opponent replay: {} avatar decisions, {} frames exact; the snap to the representative "
                  "action moves the opponent's next arrival point by {:.3f} m (median), {:.3f} m (90th percentile)",
                  decisions, frames, snapGap[snapGap.size() / 2], snapGap[snapGap.size() * 9 / 10]));
  CHECK(decisions == 240);
}

TEST_CASE("the struck term costs the frame a learned opponent's strike lands on the head, and no other",
          "[opponent][data]") {
  SparFixture& f = fixture();
  const StateActionModel& m = f.model;
  const TermKind* kind = app::plugins().terms.find("struck");
  REQUIRE(kind != nullptr);
  auto make = [&](const char* yaml) {
    std::unique_ptr<Term> term = kind->make(Params::read(ConfigNode::parse(yaml, "t"), kind->params, {}));
    term->bind(m);
    return term;
  };
  BodyPoint head = parseBodyPoint("head");
  rewards::bindPoint(m, head);
  // The avatar stands still in a frame of its first action; the opponent's punch whose tip
  // is nearest the head's height, its decision placed so that the tip is straight above or
  // below the head.
  const std::size_t a = 0, t = 1, frame = m.actionFrameBegin[a];
  const Eigen::Vector3d p = jointAt(m, frame, head.joint);
  REQUIRE_FALSE(m.hits.empty());
  const ActionHit* h = &m.hits.front();
  for (const ActionHit& x : m.hits)
    if (std::abs(x.y - p.y()) < std::abs(h->y - p.y())) h = &x;
  const double radius = std::abs(h->y - p.y()) + 0.02;
  REQUIRE(radius < 0.3);
  OpponentFrame o{GroundMotion{p.x() - h->x, p.z() - h->z, 0}, h->action, h->offset, 1, 0};
  const TargetState e(Eigen::Vector3d(0, 1.4, 1.2), 0, M_PI);
  const Eigen::Vector3d target = o.toAvatar(Eigen::Vector3d(h->x, h->y, h->z));
  auto at = [&](const Term& term, const OpponentFrame* opponent) {
    return term.signal(TermFrame{m, a, t, frame, target, e, 1.2, opponent});
  };
  const std::string plain = fmt::format("{{radius: {}, use_speed: false}}", radius);
  const auto struck = make(plain.c_str());
  CHECK(struck->cost());
  CHECK(at(*struck, &o) == 1);
  // Weighted by the punch's speed, as contact weighs the avatar's own.
  const auto weighted = make(fmt::format("{{radius: {}}}", radius).c_str());
  CHECK(at(*weighted, &o) >= h->weight - 1e-6);
  CHECK(at(*weighted, &o) <= 1);
  // The same punch a metre to the side, or the head the punch does not reach: no cost.
  OpponentFrame aside = o;
  aside.decision.dx += 1;
  CHECK(at(*struck, &aside) == 0);
  const auto tight = make(fmt::format("{{radius: {}, use_speed: false}}", std::abs(h->y - p.y()) * 0.5 + 1e-4).c_str());
  if (std::abs(h->y - p.y()) > 1e-3) CHECK(at(*tight, &o) == 0);
  // A frame of the action at which it throws nothing is not a hit.
  for (std::uint32_t k = 1; k <= m.actionLength(h->action); ++k) {
    const auto strikes = m.hitsOf(h->action);
    if (std::none_of(strikes.begin(), strikes.end(), [&](const ActionHit& x) { return x.offset == k; })) {
      OpponentFrame idle = o;
      idle.offset = k;
      CHECK(at(*struck, &idle) == 0);
      break;
    }
  }
  // In a reward the term costs: a bout of actions within reach of a learned opponent loses
  // what the punches it takes weigh, and never gains.
  const std::unique_ptr<Reward> reward = app::plugins().rewards.create(ConfigNode::parse(
      "{type: terms, combine: sum, terms: [{term: struck, radius: 0.2, use_speed: false, weight: 2}]}", "r"));
  reward->bind(m);
  reward->bindEnvironment(f.behaviors.front().environment.get());
  Rng rng(5);
  std::size_t costly = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const TargetState near =
        f.behaviors.front().environment->draw(Eigen::Vector3d(0, 1.4, 0.6 + 0.3 * rng.uniform()), rng);
    const double r = reward->evaluate(m, rng.below(m.actionCount()), near);
    REQUIRE(r <= 0);
    costly += r < 0;
  }
  CHECK(costly > 0);
  // The scripted opponent (environment `opponent`) throws every punch at every moment: on
  // top of the avatar it lands, 5 m away it does not.
  CHECK(struck->signal(
            TermFrame{m, a, t, frame, target, TargetState(Eigen::Vector3d(0, 1.4, 0), 0, M_PI), 0, nullptr}) == 1);
  CHECK(struck->signal(
            TermFrame{m, a, t, frame, target, TargetState(Eigen::Vector3d(0, 1.4, 5), 0, M_PI), 5, nullptr}) == 0);
}

TEST_CASE(
    "eval's success conditions see a learned opponent as the reward terms do: its head where it is at each frame, "
    "the strikes it throws",
    "[opponent][data]") {
  SparFixture& f = fixture();
  const StateActionModel& m = f.model;
  const EnvironmentModel& environment = *f.behaviors.front().environment;
  const TrackedOpponent* opponent = environment.as<TrackedOpponent>();
  REQUIRE(opponent);
  const ConditionRegistry& kinds = app::plugins().conditions;
  auto criterion = [&](const char* yaml) {
    SuccessCriterion c = SuccessCriterion::read(ConfigNode::parse(yaml, "c"), nlohmann::json::array(), kinds);
    c.bind(m);
    return c;
  };
  const SuccessCriterion contact = criterion("{term: contact, radius: 0.2}");
  const SuccessCriterion avoid = criterion("{term: avoid, clear: 0.1}");
  auto term = [&](const char* name, const char* yaml) {
    const TermKind* kind = app::plugins().terms.find(name);
    std::unique_ptr<Term> t = kind->make(Params::read(ConfigNode::parse(yaml, "t"), kind->params, {}));
    t->bind(m);
    return t;
  };
  const auto contactTerm = term("contact", "{radius: 0.2, use_speed: false}");
  const auto avoidTerm = term("avoid", "{clear: 0.1}");
  BodyPoint head = parseBodyPoint("head");
  rewards::bindPoint(m, head);
  Rng rng(11);
  std::size_t landed = 0, unlike = 0, cornered = 0;
  std::vector<OpponentFrame> track;
  for (int trial = 0; trial < 3000; ++trial) {
    // The opponent within reach, in front: where strikes land both ways.
    const double r = 0.5 + 0.5 * rng.uniform(), angle = 0.6 * (rng.uniform() - 0.5);
    const TargetState e = environment.draw(Eigen::Vector3d(r * std::sin(angle), 1.4, r * std::cos(angle)), rng);
    const std::uint32_t s = rng.below(m.stateCount());
    const std::size_t a = m.stateActionBegin[s] + rng.below(m.stateActionBegin[s + 1] - m.stateActionBegin[s]);
    opponent->track(m, a, e, track);
    // The first frame each term says so, read as the reward reads the track.
    std::uint32_t firstHit = 0, firstClear = 0;
    for (std::uint32_t t = 1; t <= m.actionLength(a); ++t) {
      const OpponentFrame& o = track[t - 1];
      const Eigen::Vector3d target = opponentTarget(m, o, head.joint, e.position.y());
      const TermFrame frame{m, a, t, m.actionFrameBegin[a] + t - 1, target, e, r, &o};
      if (firstHit == 0 && contactTerm->signal(frame) > 0) firstHit = t;
      if (firstClear == 0 && avoidTerm->signal(frame) == 1) firstClear = t;
    }
    SuccessCriterion::Tracker hits(contact, m.frameTime), clears(avoid, m.frameTime);
    const std::uint32_t hitAt = hits.play(m, a, e, opponent);
    CHECK(hitAt == firstHit);
    CHECK(clears.play(m, a, e, opponent) == firstClear);
    landed += hitAt > 0;
    cornered += firstClear != 1;
    // Without the environment the head stands where it was at the decision.
    SuccessCriterion::Tracker still(contact, m.frameTime);
    unlike += still.play(m, a, e) != hitAt;
  }
  WARN(
      fmt::format("of 3000 actions within reach of a learned opponent, {} land a punch on its head, {} start "
                  "inside its strikes; a head left standing at the decision differs in {}",
                  landed, cornered, unlike));
  CHECK(landed > 0);
  CHECK(cornered > 0);
  CHECK(unlike > 0);
}

namespace {

// spar_learned.yaml shrunk for tests: 2 sectors x 2 rings x 2 facings, one phase: 8
// positions x 117 opponent states, 936 vertices (1.3 M table entries). The checks hold for
// any grid; with the finer 3 x 2 x 3 (2,106 vertices) the self-play test took 128 s of the
// Release suite under ctest -j2 on the 2-core machine, the longest test there.
const char* kSmallSpar =
    " --set behaviors.spar.discretizer.sectors=2 --set behaviors.spar.discretizer.rings=2"
    " --set behaviors.spar.discretizer.headings=2 --set behaviors.spar.environment.phases=1";
constexpr std::size_t kSmallPositions = 8;

struct SparSandbox : test::CliSandbox {
  SparSandbox() : CliSandbox("mgrl_learned_opponent") {}
  test::Run run(const std::string& arguments) { return test::runMgrl(arguments + where(), dir()); }
  std::string scenario() const {
    return test::shellWord(std::string(test::sourceDirectory()) + "/scenarios/spar_learned.yaml");
  }
  /// `mgrl train` on the small grid with `sets` (" --set K=V ..."), its report on stdout,
  /// the bundle in `out`.
  test::Run trainSmall(const std::string& sets, const std::string& out) {
    return run("train " + scenario() + kSmallSpar + sets + " --json --out " + test::shellWord(path(out)));
  }
};

}  // namespace

TEST_CASE("mgrl train runs self-play rounds against a learned opponent, keeps every round and reports the gap",
          "[opponent][cli][data][slow]") {
  SparSandbox box;
  // Three rounds, the third against the mean of the first two (against: average).
  const test::Run trained = box.trainSmall(
      " --set behaviors.spar.environment.rounds=3 --set behaviors.spar.environment.against=average", "policy");
  INFO(trained.err);
  REQUIRE(trained.status == 0);
  const nlohmann::json report = trained.report();
  const nlohmann::json& rounds = report["behaviors"]["spar"]["rounds"];
  REQUIRE(rounds.size() == 3);
  CHECK(rounds[0]["opponent"] == "scripted");
  CHECK_FALSE(rounds[0].contains("gap"));
  CHECK(rounds[1]["opponent"] == "round 1");
  CHECK(rounds[2]["opponent"] == "rounds 1-2 mean");
  for (std::size_t k = 1; k < 3; ++k) {
    INFO("round " << k + 1);
    CHECK(rounds[k]["gap"].get<double>() ==
          Approx(rounds[k]["return"].get<double>() - rounds[k]["previous_return"].get<double>()));
    // Round k is a best response to the table its opponent plays: against it, it does at
    // least as well as that table's own greedy policy (up to the grid's interpolation).
    CHECK(rounds[k]["gap"].get<double>() > -0.05 * rounds[k]["return"].get<double>());
    // On the grid, where the round was trained, the best response gains exactly: at least 0
    // (up to the evaluation's tolerance, 0.01).
    REQUIRE(rounds[k].contains("table_gap"));
    CHECK(rounds[k]["table_gap"].get<double>() > -0.01);
    // And the earlier table is far from its best answer (14.8 and 8.5 here): a round scored
    // against its own table instead would gain nothing.
    CHECK(rounds[k]["table_gap"].get<double>() > 1.0);
    // The punches each table's policy lands and takes in those episodes, a minute.
    for (const char* key : {"landed_per_min", "taken_per_min", "previous_landed_per_min", "previous_taken_per_min"})
      CHECK(rounds[k][key].get<double>() >= 0);
  }
  // Round 1 plays the scripted pursuer, which punches whenever it is in reach: it takes
  // several times the punches it lands (4.9 against 0.7 a minute here).
  CHECK(rounds[0]["taken_per_min"].get<double>() > 2 * rounds[0]["landed_per_min"].get<double>());
  bool exchanged = false;
  for (const nlohmann::json& r : rounds)
    exchanged |= r["landed_per_min"].get<double>() + r["taken_per_min"].get<double>() > 0;
  CHECK((trained.err.find("punches a minute") != std::string::npos) == exchanged);
  CHECK(trained.err.find("train spar: self-play round 2 of 3, against round 1's table") != std::string::npos);
  CHECK(trained.err.find("train spar: self-play round 3 of 3, against rounds 1-2 mean's table") != std::string::npos);
  CHECK(trained.err.find("train spar: round 2: best-response gap ") != std::string::npos);
  CHECK(trained.err.find(" on the grid against round 1's table (its value less that of the opponent's own table") !=
        std::string::npos);
  CHECK(trained.err.find("in 200 episodes of 10 s it returns ") != std::string::npos);
  CHECK(report["behaviors"]["spar"]["vertices"] == kSmallPositions * 117);

  // Every round is in the bundle, and they differ: the opponent changed between them.
  const nlohmann::json manifest = nlohmann::json::parse(test::readText(box.path("policy") / "manifest.json"));
  CHECK(manifest.dump().find("spar-round1") != std::string::npos);
  CHECK(manifest.dump().find("spar-round2") != std::string::npos);
  CHECK(test::readText(box.path("policy") / "spar.q.npy") != test::readText(box.path("policy") / "spar-round1.q.npy"));
  CHECK(test::readText(box.path("policy") / "spar.q.npy") != test::readText(box.path("policy") / "spar-round2.q.npy"));

  // The gap on the grid needs the problem's optimum: a Q-learned round gets the episodes'
  // figures only.
  const test::Run learned = box.trainSmall(
      " --set behaviors.spar.environment.rounds=2 --set "
      "behaviors.spar.learner.type=q_learning --set "
      "behaviors.spar.learner.budget=20000",
      "q");
  INFO(learned.err);
  REQUIRE(learned.status == 0);
  const nlohmann::json qRound = learned.report()["behaviors"]["spar"]["rounds"].at(1);
  CHECK(qRound.contains("gap"));
  CHECK_FALSE(qRound.contains("table_gap"));
  CHECK(learned.err.find("on the grid") == std::string::npos);

  // The opponent can play a bundle's table (here round 2's) from round 1 on.
  const test::Run against = box.run("train " + box.scenario() + kSmallSpar +
                                    " --set behaviors.spar.environment.policy=" + test::shellWord(box.path("policy")) +
                                    " --out " + test::shellWord(box.path("next")));
  INFO(against.err);
  CHECK(against.status == 0);
  CHECK(test::readText(box.path("next") / "spar.q.npy") != test::readText(box.path("policy") / "spar-round1.q.npy"));

  // Two policies spar in the world: the first of each pair plays --policy, the second
  // --partner-policy, each told what the other is doing; the hits are counted per side.
  const test::Run bout =
      box.run("simulate " + box.scenario() + kSmallSpar + " --seconds 20 --avatars 4 --json --policy " +
              test::shellWord(box.path("policy")) + " --partner-policy " + test::shellWord(box.path("next")));
  const nlohmann::json sides = bout.report();
  REQUIRE(sides.contains("hits_by_side"));
  CHECK(sides["hits_by_side"]["policy"].get<std::size_t>() +
            sides["hits_by_side"]["partner_policy"].get<std::size_t>() ==
        sides["hits"].get<std::size_t>());
  CHECK(sides["partner_policy"] == box.path("next").string());
  // Any two rounds spar: the first avatar of each pair plays round 2, the partner round 1.
  const test::Run rounds21 =
      box.run("simulate " + box.scenario() + kSmallSpar + " --seconds 20 --avatars 2 --json --policy " +
              test::shellWord(box.path("policy")) + " --round 2 --partner-policy " +
              test::shellWord(box.path("policy")) + " --partner-round 1");
  INFO(rounds21.err);
  REQUIRE(rounds21.status == 0);
  CHECK(rounds21.report()["round"] == 2);
  CHECK(rounds21.report()["partner_round"] == 1);
  // A round the bundle does not have is refused, naming what it has.
  const test::Run round9 = box.run("simulate " + box.scenario() + kSmallSpar + " --seconds 1 --policy " +
                                   test::shellWord(box.path("policy")) + " --round 9");
  CHECK(round9.status != 0);
  CHECK(round9.lastErrorLine().find("expected self-play round 9's table for behaviour 'spar' (spar-round9), found "
                                    "only spar, spar-round1") != std::string::npos);
  // A partner policy needs policies on both sides.
  const test::Run random = box.run("simulate " + box.scenario() + kSmallSpar +
                                   " --controller random --partner-policy " + test::shellWord(box.path("next")));
  CHECK(random.status != 0);
  CHECK(random.lastErrorLine().find("--partner-policy: expected --controller policy") != std::string::npos);
}

TEST_CASE(
    "a learned opponent refuses a grid with speed layers and a missing policy bundle, each at its key, simulate "
    "refuses a partner it cannot use",
    "[opponent][cli][data]") {
  SparSandbox box;
  const test::Run speeds = box.run("train " + box.scenario() + " --set behaviors.spar.discretizer.speeds=3 --out " +
                                   test::shellWord(box.path("a")));
  CHECK(speeds.status != 0);
  CHECK(speeds.lastErrorLine().find("behaviors.spar.discretizer.type: a learned opponent's 234 states as grid layers: "
                                    "polar_velocity: expected one speed layer under a learned opponent's layers, "
                                    "found 3 (set speeds: 1)") != std::string::npos);
  const test::Run missing = box.run("train " + box.scenario() + " --set behaviors.spar.environment.policy=" +
                                    test::shellWord(box.path("nothing")) + " --out " + test::shellWord(box.path("b")));
  CHECK(missing.status != 0);
  CHECK(missing.lastErrorLine().find("behaviors.spar.environment.policy") != std::string::npos);
  CHECK(missing.lastErrorLine().find("no policy bundle here") != std::string::npos);
  CHECK_FALSE(fs::exists(box.path("b")));
  // Too large for --max-memory: refused before anything is tabulated, saying what multiplies it.
  const test::Run big =
      box.run("train " + box.scenario() + " --max-memory 0.5 --out " + test::shellWord(box.path("c")));
  CHECK(big.status != 0);
  CHECK(big.lastErrorLine().find("behaviors.spar: training on a polar_velocity grid of 33696 vertices (a learned "
                                 "opponent's 234 states times 144 positions") != std::string::npos);
  CHECK(big.lastErrorLine().find("expected at most 500.0 MB (--max-memory)") != std::string::npos);
  // The rounds' tables count: the three finished, the previous round's copy and the mean,
  // and policy evaluation's 1.5 more than value iteration's pair (train_command.cpp).
  CHECK(big.lastErrorLine().find("6.5 more tables held by 4 self-play rounds") != std::string::npos);
  CHECK(big.err.find("tabulated") == std::string::npos);
  // simulate: a partner's round without a partner bundle, a partner outside a sparring world.
  const test::Run round = box.run("simulate " + box.scenario() + " --controller random --partner-round 1");
  CHECK(round.status != 0);
  CHECK(round.lastErrorLine().find("--partner-round: expected --partner-policy DIR as well") != std::string::npos);
  const test::Run ownRound = box.run("simulate " + box.scenario() + " --controller random --round 1");
  CHECK(ownRound.status != 0);
  CHECK(ownRound.lastErrorLine().find("--round: expected --controller policy (a self-play round's tables), found "
                                      "random") != std::string::npos);
  const test::Run targets = box.run("simulate " + box.scenario() + " --controller random --set world.mode=targets" +
                                    " --partner-policy " + test::shellWord(box.path("nothing")));
  CHECK(targets.status != 0);
  CHECK(targets.lastErrorLine().find("--partner-policy: expected a sparring world (world.mode: sparring), found "
                                     "targets") != std::string::npos);
}

TEST_CASE(
    "self-play trains each round after the first on a behaviour of its own: the one given and the session's still "
    "play the scenario's opponent",
    "[opponent][learning][data]") {
  test::TempDir temp("self-play-own-rounds");
  SessionOptions options;
  options.plugins = &builtinPlugins();
  options.scenario = std::string(test::sourceDirectory()) + "/scenarios/spar_learned.yaml";
  options.dataDir = test::mocap();
  options.cacheDir = temp.path;
  options.sets = {"behaviors.spar.discretizer.sectors=2", "behaviors.spar.discretizer.rings=2",
                  "behaviors.spar.discretizer.headings=2", "behaviors.spar.environment.phases=1",
                  "behaviors.spar.environment.rounds=2"};
  const auto session = openSession(options, {.motion = false});
  const std::vector<Behavior> built =
      buildBehaviors(session->scenario, session->plugins(), session->model(), session->graph.key, "spar");
  const Behavior& spar = built.at(0);
  auto opponentOf = [](const Behavior& b) { return std::as_const(*b.environment).as<SelfPlayOpponent>()->policyKey(); };
  REQUIRE(opponentOf(spar) == "scripted");
  TrainSettings settings;
  settings.save = false;
  settings.learner = session->plugins().learners.create(ConfigNode::parse("{type: value_iteration}", "test"));
  const Trained trained = trainBehavior(*session, spar, session->scenario, settings);
  CHECK(trained.bundle.behaviors.count("spar-round1") == 1);
  CHECK(trained.bundle.behaviors.count("spar") == 1);
  REQUIRE(trained.report["behaviors"]["spar"]["rounds"].size() == 2);
  // Round 2 played round 1's table; neither model that was built before training changed.
  CHECK(opponentOf(spar) == "scripted");
  CHECK(opponentOf(session->behaviors.at(0)) == "scripted");
  CHECK(trained.bundle.behaviors.at("spar").table != trained.bundle.behaviors.at("spar-round1").table);
}

TEST_CASE("a negative best-response gap is explained in train's round line", "[opponent][learning]") {
  CHECK(gapNote(0.33, true).empty());
  CHECK(gapNote(0.0, true).empty());
  CHECK(gapNote(-0.47, true).find("negative: the grid's best response is not the best") != std::string::npos);
  CHECK(gapNote(-0.47, true).find("a finer grid narrows this") != std::string::npos);
  // A table that is not the grid's optimum (Q-learning) is not called its best response.
  CHECK(gapNote(-0.47, false).find("best response") == std::string::npos);
  CHECK(gapNote(-0.47, false).find("does worse in these episodes") != std::string::npos);
}

TEST_CASE("self-play against: average plays the entry-by-entry mean of the earlier rounds' tables",
          "[opponent][learning]") {
  StateActionModel m;  // what a table's layout depends on: state 0 has actions 0 and 1, state 1 action 2
  m.actionFrom = {0, 0, 1};
  m.actionTo = {1, 0, 0};
  m.stateActionBegin = {0, 2, 3};
  std::vector<QTable> rounds(3, QTable(m, 4));
  for (std::size_t k = 0; k < rounds.size(); ++k)
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t v = 0; v < 4; ++v)
        rounds[k].at(a, v) = static_cast<float>((k + 1) * (a + 1)) + 0.25F * static_cast<float>(v * k);
  std::shared_ptr<const QTable> mean;
  for (std::size_t k = 0; k < rounds.size(); ++k) mean = meanOfRounds(mean.get(), rounds[k], static_cast<int>(k + 1));
  for (std::size_t a = 0; a < 3; ++a)
    for (std::size_t v = 0; v < 4; ++v) {
      const double expected = (rounds[0].at(a, v) + rounds[1].at(a, v) + rounds[2].at(a, v)) / 3.0;
      CHECK(mean->at(a, v) == Approx(expected).epsilon(1e-6));
    }
  // The first round's mean is its own table; a table of another layout is refused.
  CHECK(*meanOfRounds(nullptr, rounds[1], 1) == rounds[1]);
  const QTable other(m, 5);
  CHECK_THROWS_WITH(meanOfRounds(mean.get(), other, 4),
                    Catch::Contains("round 4's table has 3 actions x 5 vertices, the earlier rounds' 3 x 4"));
}

}  // namespace mgrl::learned_opponent_test
