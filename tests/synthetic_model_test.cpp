// The synthetic state-action model for benchmarks: the paper's sizes (437 states, 27,072
// actions of 5 to 40 frames at 15 fps), every invariant checkModel knows, a strongly
// connected graph, a frame graph that agrees with the actions, boxing-like hits, and the
// same arrays for the same seed.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <queue>
#include <set>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "synthetic_model.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace synthetic_model_test {

using namespace mgrl;
using Catch::Contains;

namespace {

// The seed-sized model, built once for the file.
const StateActionModel& seedSized() {
  static const StateActionModel model = makeSyntheticModel(SyntheticModelSpec{});
  return model;
}

// States reached from `start` along actions, forwards or (reverse) backwards.
std::size_t reachable(const StateActionModel& m, std::uint32_t start, bool reverse) {
  std::vector<std::vector<std::uint32_t>> next(m.stateCount());
  for (std::size_t a = 0; a < m.actionCount(); ++a)
    if (reverse)
      next[m.actionTo[a]].push_back(m.actionFrom[a]);
    else
      next[m.actionFrom[a]].push_back(m.actionTo[a]);
  std::vector<std::uint8_t> seen(m.stateCount(), 0);
  std::queue<std::uint32_t> queue;
  queue.push(start);
  seen[start] = 1;
  std::size_t count = 1;
  while (!queue.empty()) {
    const std::uint32_t s = queue.front();
    queue.pop();
    for (std::uint32_t t : next[s])
      if (!seen[t]) {
        seen[t] = 1;
        ++count;
        queue.push(t);
      }
  }
  return count;
}

bool sameArrays(const StateActionModel& a, const StateActionModel& b) {
  auto sameHits = [](const std::vector<ActionHit>& x, const std::vector<ActionHit>& y) {
    return std::equal(x.begin(), x.end(), y.begin(), y.end(), [](const ActionHit& p, const ActionHit& q) {
      return p.action == q.action && p.offset == q.offset && p.hand == q.hand && p.x == q.x && p.y == q.y &&
             p.z == q.z && p.weight == q.weight;
    });
  };
  return a.frameTime == b.frameTime && a.framesTotal == b.framesTotal && a.clipOffset == b.clipOffset &&
         a.componentFrames == b.componentFrames && a.transitions == b.transitions &&
         a.transitionDistance == b.transitionDistance && a.stateFrame == b.stateFrame &&
         a.actionFrom == b.actionFrom && a.actionTo == b.actionTo && a.actionFrameBegin == b.actionFrameBegin &&
         a.actionDisplacement == b.actionDisplacement && a.stateActionBegin == b.stateActionBegin &&
         a.actionFrames == b.actionFrames && a.frameRoot == b.frameRoot && a.frameCentroid == b.frameCentroid &&
         a.frameEntersTransition == b.frameEntersTransition && sameHits(a.hits, b.hits) &&
         a.actionHitBegin == b.actionHitBegin && std::equal(a.centroid, a.centroid + 3, b.centroid) &&
         a.maxHitSpeed_mps == b.maxHitSpeed_mps;
}

// Every edge an action walks (from its state's frame through its frames) is either a clip's
// own i -> i + 1 or a listed transition, and the played frame is flagged exactly when it
// enters through a transition. Returns the number of edges that break this.
std::size_t frameGraphMismatches(const StateActionModel& m) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> transitions;
  for (std::size_t e = 0; 2 * e < m.transitions.size(); ++e)
    transitions.insert({m.transitions[2 * e], m.transitions[2 * e + 1]});
  auto clipOf = [&](std::uint32_t f) {
    return std::upper_bound(m.clipOffset.begin(), m.clipOffset.end(), f) - m.clipOffset.begin();
  };
  std::size_t bad = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    std::uint32_t previous = m.stateFrame[m.actionFrom[a]];
    for (std::size_t i = m.actionFrameBegin[a]; i < m.actionFrameBegin[a + 1]; ++i) {
      const std::uint32_t v = m.actionFrames[i];
      const bool continues = v == previous + 1 && clipOf(v) == clipOf(previous);
      const bool listed = transitions.count({previous, v}) != 0;
      if (continues == listed || m.frameEntersTransition[i] != (listed ? 1 : 0)) ++bad;
      previous = v;
    }
  }
  return bad;
}

}  // namespace

TEST_CASE("the seed-sized synthetic model has the paper's sizes and passes checkModel", "[synthetic]") {
  const StateActionModel& m = seedSized();
  REQUIRE(m.stateCount() == 437);
  REQUIRE(m.actionCount() == 27072);
  REQUIRE_NOTHROW(checkModel(m, "synthetic"));
  CHECK(m.frameTime == Approx(1.0 / 15));

  // Every state has out-actions, their number varies around 27072 / 437 = 62.
  std::vector<std::uint32_t> out(m.stateCount());
  for (std::size_t s = 0; s < m.stateCount(); ++s) out[s] = m.stateActionBegin[s + 1] - m.stateActionBegin[s];
  const auto [fewest, most] = std::minmax_element(out.begin(), out.end());
  CHECK(*fewest >= 1);
  CHECK(*most > 2 * 62);
  CHECK(*fewest < 62 / 2);
  CHECK(std::set<std::uint32_t>(out.begin(), out.end()).size() > 50);

  // A state's frame plus each action's own frames before its end state.
  std::size_t ownFrames = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) ownFrames += m.actionLength(a) - 1;
  CHECK(m.framesTotal == m.stateCount() + ownFrames);
  CHECK(m.hits.size() > 0);
  CHECK(m.maxHitSpeed_mps > 0);
}

TEST_CASE("synthetic action lengths are uniform over [minFrames, maxFrames]", "[synthetic]") {
  const StateActionModel& m = seedSized();
  std::vector<std::size_t> count(41, 0);
  std::size_t outside = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const std::size_t n = m.actionLength(a);
    if (n < 5 || n > 40)
      ++outside;
    else
      ++count[n];
  }
  CHECK(outside == 0);
  CHECK(count[5] > 0);
  CHECK(count[40] > 0);
  // 27072 / 36 = 752 per length; binomial sd about 27.
  for (std::size_t n = 5; n <= 40; ++n) {
    CAPTURE(n);
    CHECK(count[n] > 600);
    CHECK(count[n] < 900);
  }
}

TEST_CASE("every synthetic state reaches every other state", "[synthetic]") {
  const StateActionModel& m = seedSized();
  for (std::uint32_t start : {0u, 218u}) {
    CAPTURE(start);
    CHECK(reachable(m, start, false) == m.stateCount());
    CHECK(reachable(m, start, true) == m.stateCount());
  }
}

TEST_CASE("synthetic frames form the graph the actions walk", "[synthetic]") {
  const StateActionModel& m = seedSized();
  // Only an action's last frame is a state's, and the actions cover every frame.
  std::vector<std::uint8_t> covered(m.framesTotal, 0);
  std::size_t stateInside = 0, notEntered = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const auto frames = m.framesOf(a);
    for (std::size_t i = 0; i + 1 < frames.size(); ++i)
      stateInside += std::binary_search(m.stateFrame.begin(), m.stateFrame.end(), frames[i]);
    for (std::uint32_t f : frames) covered[f] = 1;
    notEntered += m.frameEntersTransition[m.actionFrameBegin[a]] != 1;
  }
  CHECK(stateInside == 0);
  CHECK(std::count(covered.begin(), covered.end(), 1) == static_cast<long>(m.framesTotal));
  CHECK(m.componentFrames.size() == m.framesTotal);
  CHECK(notEntered == 0);  // a decision always leaves its state's clip
  CHECK(frameGraphMismatches(m) == 0);
}

TEST_CASE("a synthetic action's displacement is its last root and the centroid rides along", "[synthetic]") {
  const StateActionModel& m = seedSized();
  const Eigen::Vector3d centroid(m.centroid[0], m.centroid[1], m.centroid[2]);
  std::size_t displacementOff = 0, centroidOff = 0;
  double largestStep = 0, largestTurn = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const std::size_t last = m.actionFrameBegin[a + 1] - 1;
    for (int k = 0; k < 3; ++k) displacementOff += m.actionDisplacement[3 * a + k] != m.frameRoot[3 * last + k];
    for (std::size_t i = m.actionFrameBegin[a]; i <= last; ++i) {
      const GroundMotion root{m.frameRoot[3 * i], m.frameRoot[3 * i + 1], m.frameRoot[3 * i + 2]};
      const Eigen::Vector3d expected = transformPoint(root, centroid);
      for (int k = 0; k < 3; ++k) centroidOff += std::abs(m.frameCentroid[3 * i + k] - expected[k]) > 1e-5;
      const double px = i > m.actionFrameBegin[a] ? m.frameRoot[3 * i - 3] : 0;
      const double pz = i > m.actionFrameBegin[a] ? m.frameRoot[3 * i - 2] : 0;
      const double pyaw = i > m.actionFrameBegin[a] ? m.frameRoot[3 * i - 1] : 0;
      largestStep = std::max(largestStep, std::hypot(root.dx - px, root.dz - pz));
      largestTurn = std::max(largestTurn, std::abs(std::remainder(root.dyaw - pyaw, 2 * M_PI)));
    }
  }
  CHECK(displacementOff == 0);
  CHECK(centroidOff == 0);
  // A smooth path: no frame jumps further than a boxer's root moves in 1/15 s.
  CHECK(largestStep < 0.2);
  CHECK(largestTurn < 1.0);
  // The centroid sits in front of the boxer at chest height.
  CHECK(m.centroid[2] > 0.2);
  CHECK(m.centroid[1] > 0.8);
}

TEST_CASE("synthetic root motion has the boxing graph's statistics", "[synthetic]") {
  const StateActionModel& m = seedSized();
  // The boxer stays in place: displacement sd about 0.1 m and 0.5 rad whatever the length.
  double sumX = 0, sumXX = 0, sumYaw = 0, sumYawYaw = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const GroundMotion d = m.displacement(a);
    sumX += d.dx;
    sumXX += d.dx * d.dx;
    sumYaw += d.dyaw;
    sumYawYaw += d.dyaw * d.dyaw;
  }
  const double n = static_cast<double>(m.actionCount());
  const double sdX = std::sqrt(sumXX / n - (sumX / n) * (sumX / n));
  const double sdYaw = std::sqrt(sumYawYaw / n - (sumYaw / n) * (sumYaw / n));
  CHECK(sdX > 0.05);
  CHECK(sdX < 0.2);
  CHECK(sdYaw > 0.3);
  CHECK(sdYaw < 0.9);
}

TEST_CASE("synthetic hits are as frequent and placed as in the boxing graph", "[synthetic]") {
  const SyntheticModelSpec spec;
  const StateActionModel& m = seedSized();
  std::size_t withHits = 0, shortWithHits = 0, outside = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const auto hits = m.hitsOf(a);
    if (hits.empty()) continue;
    ++withHits;
    shortWithHits += m.actionLength(a) * m.frameTime < spec.minHitActionSeconds - 1e-9;
    for (const ActionHit& h : hits) {
      const BoundedNormal& angle = spec.hitAngle_rad[h.hand];
      const double theta = std::atan2(h.x, h.z), distance = std::hypot(h.x, h.z);
      outside += theta < angle.min - 1e-5 || theta > angle.max + 1e-5;
      outside += distance < spec.hitDistance_m.min - 1e-5 || distance > spec.hitDistance_m.max + 1e-5;
      outside += h.y < spec.hitHeight_m.min - 1e-5 || h.y > spec.hitHeight_m.max + 1e-5;
      outside += h.weight < spec.hitWeight.min - 1e-6 || h.weight > spec.hitWeight.max;
    }
  }
  const double fraction = static_cast<double>(withHits) / static_cast<double>(m.actionCount());
  CHECK(fraction == Approx(spec.hitActionFraction).margin(0.005));
  CHECK(shortWithHits == 0);
  CHECK(outside == 0);
  // Boxing at 15 fps: 3.7 hitting frames per action with hits (punches of about 2 frames).
  const double perAction = static_cast<double>(m.hits.size()) / static_cast<double>(withHits);
  CHECK(perAction > 2);
  CHECK(perAction < 6);
  std::size_t right = 0;
  for (const ActionHit& h : m.hits) right += h.hand;
  CHECK(static_cast<double>(right) / static_cast<double>(m.hits.size()) == Approx(spec.rightHandFraction).margin(0.05));

  SyntheticModelSpec none;
  none.hitActionFraction = 0;
  none.actions = 2000;
  const StateActionModel quiet = makeSyntheticModel(none);
  CHECK(quiet.hits.empty());
  CHECK(quiet.maxHitSpeed_mps > 0);
  REQUIRE_NOTHROW(checkModel(quiet, "synthetic"));
}

TEST_CASE("the same seed gives the same synthetic model, another seed another", "[synthetic]") {
  SyntheticModelSpec spec;
  spec.states = 60;
  spec.actions = 2500;
  const StateActionModel a = makeSyntheticModel(spec);
  const StateActionModel b = makeSyntheticModel(spec);
  CHECK(sameArrays(a, b));
  CHECK(sameArrays(seedSized(), makeSyntheticModel(SyntheticModelSpec{})));

  spec.seed = 2;
  const StateActionModel c = makeSyntheticModel(spec);
  REQUIRE_NOTHROW(checkModel(c, "synthetic"));
  CHECK(c.actionCount() == a.actionCount());
  CHECK_FALSE(sameArrays(a, c));
  CHECK(c.actionTo != a.actionTo);
  CHECK(c.stateActionBegin != a.stateActionBegin);
  CHECK(c.frameRoot != a.frameRoot);
}

TEST_CASE("small synthetic models are valid and strongly connected too", "[synthetic]") {
  struct Case {
    std::size_t states, actions;
    std::uint32_t minFrames, maxFrames;
  };
  for (const Case& c : {Case{5, 20, 5, 40}, Case{5, 20, 1, 3}, Case{1, 1, 1, 1}, Case{1, 7, 2, 9}, Case{8, 8, 3, 6},
                        Case{2, 40, 1, 1}}) {
    for (std::uint64_t seed : {1u, 7u, 123u}) {
      CAPTURE(c.states, c.actions, c.minFrames, c.maxFrames, seed);
      SyntheticModelSpec spec;
      spec.states = c.states;
      spec.actions = c.actions;
      spec.minFrames = c.minFrames;
      spec.maxFrames = c.maxFrames;
      spec.seed = seed;
      const StateActionModel m = makeSyntheticModel(spec);
      REQUIRE_NOTHROW(checkModel(m, "synthetic"));
      CHECK(m.stateCount() == c.states);
      CHECK(m.actionCount() == c.actions);
      for (std::size_t s = 0; s < m.stateCount(); ++s) CHECK(m.stateActionBegin[s + 1] > m.stateActionBegin[s]);
      for (std::size_t a = 0; a < m.actionCount(); ++a) {
        CHECK(m.actionLength(a) >= c.minFrames);
        CHECK(m.actionLength(a) <= c.maxFrames);
      }
      CHECK(reachable(m, 0, false) == c.states);
      CHECK(reachable(m, 0, true) == c.states);
      CHECK(frameGraphMismatches(m) == 0);
    }
  }
}

TEST_CASE("an impossible synthetic spec is refused with the member it breaks", "[synthetic]") {
  SyntheticModelSpec spec;
  std::string message;
  SECTION("fewer actions than states") {
    spec.actions = 100;
    message = "synthetic model: actions: expected at least states = 437 (every state needs an out-action), found 100";
  }
  SECTION("no states") {
    spec.states = 0;
    message = "synthetic model: states: expected at least 1, found 0";
  }
  SECTION("frame range upside down") {
    spec.minFrames = 10;
    spec.maxFrames = 9;
    message = "synthetic model: maxFrames: expected at least minFrames = 10, found 9";
  }
  SECTION("no frame rate") {
    spec.fps = 0;
    message = "synthetic model: fps: expected a frame rate above 0, found 0";
  }
  SECTION("a distribution whose mean lies outside its bounds") {
    spec.hitDistance_m.mean = 2;
    message = "synthetic model: hitDistance_m.mean: expected a value in [min, max] = [0.27, 1.26], found 2";
  }
  SECTION("a hit weight that can be 0") {
    spec.hitWeight.min = 0;
    spec.hitWeight.mean = 0.5;
    message = "synthetic model: hitWeight.min: expected a weight above 0";
  }
  REQUIRE_THROWS_AS(makeSyntheticModel(spec), Error);
  REQUIRE_THROWS_WITH(makeSyntheticModel(spec), Contains(message));
}

}  // namespace synthetic_model_test
