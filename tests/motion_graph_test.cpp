// The motion graph and state-action model on the real capture (paper sec. 3, 6.3).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <queue>
#include <tuple>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/graph/frame_distance.hpp"
#include "mgrl/graph/graph_cache.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/graph/playback.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/motion/roles.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace motion_graph_test {

using namespace mgrl;

namespace {

std::filesystem::path scenarioFile(const std::string& name) {
  return std::filesystem::path(MGRL_SOURCE_DIR) / "scenarios" / (name + ".yaml");
}

// The boxing scenario's capture and graph, built once for the file.
struct Boxing {
  Scenario scenario = loadScenario(scenarioFile("boxing"), test::mocap());
  MotionDatabase db = loadMotionDatabase(scenario.motion);
  GraphBuildReport report;
  StateActionModel model = buildStateActionModel(db, scenario.graph, &report);
};

const Boxing& boxing() {
  static const Boxing instance;
  return instance;
}

}  // namespace

TEST_CASE("every state of the boxing graph reaches every other state", "[graph][data]") {
  const StateActionModel& m = boxing().model;
  REQUIRE(m.stateCount() > 1);
  for (std::uint32_t start : {0u, static_cast<std::uint32_t>(m.stateCount() / 2)}) {
    std::vector<std::uint8_t> seen(m.stateCount(), 0), back(m.stateCount(), 0);
    std::queue<std::uint32_t> queue;
    queue.push(start);
    seen[start] = 1;
    while (!queue.empty()) {
      const std::uint32_t s = queue.front();
      queue.pop();
      for (std::uint32_t a = m.stateActionBegin[s]; a < m.stateActionBegin[s + 1]; ++a)
        if (!seen[m.actionTo[a]]) {
          seen[m.actionTo[a]] = 1;
          queue.push(m.actionTo[a]);
        }
    }
    CHECK(std::count(seen.begin(), seen.end(), 1) == static_cast<long>(m.stateCount()));
    // And every state reaches `start`: search the reversed edges.
    queue.push(start);
    back[start] = 1;
    while (!queue.empty()) {
      const std::uint32_t s = queue.front();
      queue.pop();
      for (std::size_t a = 0; a < m.actionCount(); ++a)
        if (m.actionTo[a] == s && !back[m.actionFrom[a]]) {
          back[m.actionFrom[a]] = 1;
          queue.push(m.actionFrom[a]);
        }
    }
    CHECK(std::count(back.begin(), back.end(), 1) == static_cast<long>(m.stateCount()));
  }
}

TEST_CASE("every action ends at a state and the actions cover the component", "[graph][data]") {
  const StateActionModel& m = boxing().model;
  REQUIRE_NOTHROW(checkModel(m, "boxing"));
  std::vector<std::uint8_t> covered(m.framesTotal, 0);
  std::size_t frameSum = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const auto frames = m.framesOf(a);
    REQUIRE(!frames.empty());
    CHECK(frames.back() == m.stateFrame[m.actionTo[a]]);
    // Only the last frame of an action is a state.
    for (std::size_t i = 0; i + 1 < frames.size(); ++i)
      CHECK_FALSE(std::binary_search(m.stateFrame.begin(), m.stateFrame.end(), frames[i]));
    for (std::uint32_t f : frames) covered[f] = 1;
    frameSum += frames.size();
  }
  std::vector<std::uint32_t> union_;
  for (std::uint32_t f = 0; f < m.framesTotal; ++f)
    if (covered[f]) union_.push_back(f);
  CHECK(union_ == m.componentFrames);
  CHECK(frameSum >= m.componentFrames.size());
  // The paper's boxer: tens to hundreds of states, thousands of actions.
  CHECK(m.stateCount() >= 30);
  CHECK(m.stateCount() <= 1000);
  CHECK(m.actionCount() >= 1000);
  CHECK(m.componentFrames.size() >= m.framesTotal * 8 / 10);
}

TEST_CASE("an action's root displacement matches forward kinematics of its frames", "[graph][data]") {
  const Boxing& b = boxing();
  const StateActionModel& m = b.model;
  const Skeleton& skeleton = *b.db.skeleton;
  std::vector<Eigen::Quaterniond> rot(skeleton.jointCount());
  std::vector<Eigen::Vector3d> pos(skeleton.jointCount());
  // Avatar frame straight from FK: the root projected on the ground, facing its forward axis.
  auto avatarFromFk = [&](std::uint32_t frame) {
    const std::size_t c = b.db.clipOf(frame);
    forwardKinematics(b.db.clips[c].motion, frame - b.db.offsets[c], rot, pos);
    const Eigen::Vector3d facing = rot[0] * b.db.roles.forward;
    return std::array<double, 3>{pos[0].x(), pos[0].z(), std::atan2(facing.x(), facing.z())};
  };
  std::size_t checked = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const auto frames = m.framesOf(a);
    const std::size_t begin = m.actionFrameBegin[a];
    // Walk the action edge by edge: each played frame v continues its clip from v - 1.
    double x = 0, z = 0, yaw = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const auto p = avatarFromFk(frames[i] - 1), q = avatarFromFk(frames[i]);
      const double c = std::cos(p[2]), s = std::sin(p[2]);
      const double dx = q[0] - p[0], dz = q[1] - p[1];
      const double lx = c * dx - s * dz, lz = s * dx + c * dz;  // world step in the avatar frame of v - 1
      const double cy = std::cos(yaw), sy = std::sin(yaw);
      x += cy * lx + sy * lz;
      z += -sy * lx + cy * lz;
      yaw += std::remainder(q[2] - p[2], 2 * M_PI);
      CHECK(m.frameRoot[3 * (begin + i)] == Approx(x).margin(1e-6));
      CHECK(m.frameRoot[3 * (begin + i) + 1] == Approx(z).margin(1e-6));
    }
    const GroundMotion d = m.displacement(a);
    CHECK(d.dx == Approx(x).margin(1e-6));
    CHECK(d.dz == Approx(z).margin(1e-6));
    CHECK(std::remainder(d.dyaw - yaw, 2 * M_PI) == Approx(0).margin(1e-6));
    if (++checked == 200) break;
  }
  // An action inside one clip without transitions: its displacement is simply the
  // relative avatar frame from its decision frame to its end.
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const auto frames = m.framesOf(a);
    const std::uint32_t from = m.stateFrame[m.actionFrom[a]];
    if (frames.front() != from + 1 || frames.back() != from + frames.size()) continue;
    const auto p = avatarFromFk(from), q = avatarFromFk(frames.back());
    const double c = std::cos(p[2]), s = std::sin(p[2]);
    const double dx = q[0] - p[0], dz = q[1] - p[1];
    CHECK(m.displacement(a).dx == Approx(c * dx - s * dz).margin(1e-6));
    CHECK(m.displacement(a).dz == Approx(s * dx + c * dz).margin(1e-6));
    CHECK(std::remainder(m.displacement(a).dyaw - (q[2] - p[2]), 2 * M_PI) == Approx(0).margin(1e-6));
  }
}

TEST_CASE("hits inside actions are the data's effective hits carried into the decision frame", "[graph][data]") {
  const Boxing& b = boxing();
  const StateActionModel& m = b.model;
  REQUIRE(!m.hits.empty());
  REQUIRE(m.maxHitSpeed_mps > 2);
  float heaviest = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a)
    for (const ActionHit& h : m.hitsOf(a)) {
      REQUIRE(h.action == a);
      REQUIRE(h.offset >= 1);
      REQUIRE(h.offset <= m.actionLength(a));
      const std::uint32_t v = m.actionFrames[m.actionFrameBegin[a] + h.offset - 1];
      const Clip& clip = b.db.clipAt(v);
      const auto it = std::find_if(clip.annotation.hits.begin(), clip.annotation.hits.end(), [&](const EffectiveHit& e) {
        return e.frame == b.db.localFrame(v) && static_cast<int>(e.hand) == h.hand;
      });
      REQUIRE(it != clip.annotation.hits.end());
      CHECK(h.weight == Approx(it->speed_mps / m.maxHitSpeed_mps).epsilon(1e-5));
      // Same distance from the avatar at that frame (a rigid move), same height.
      const std::size_t i = m.actionFrameBegin[a] + h.offset - 1;
      const double rx = h.x - m.frameRoot[3 * i], rz = h.z - m.frameRoot[3 * i + 1];
      CHECK(std::hypot(rx, rz) == Approx(std::hypot(it->tipAvatar.x(), it->tipAvatar.z())).margin(1e-4));
      CHECK(h.y == Approx(it->tipAvatar.y()).margin(1e-5));
      heaviest = std::max(heaviest, h.weight);
    }
  CHECK(heaviest <= 1.0f);
  // The centroid sits in front of the boxer at chest height.
  CHECK(m.centroid[2] > 0.2);
  CHECK(m.centroid[1] > 0.8);
  CHECK(m.centroid[1] < 1.8);
}

TEST_CASE("joints at action frames are the capture's joints carried into the decision frame", "[graph][data]") {
  const Boxing& b = boxing();
  const StateActionModel& m = b.model;
  const Skeleton& skeleton = *b.db.skeleton;
  REQUIRE(m.jointNames.size() == skeleton.jointCount());
  for (std::size_t j = 0; j < skeleton.jointCount(); ++j) CHECK(m.jointNames[j] == skeleton.joints()[j].name);
  const std::vector<int> roles = roleJointIndices(b.db.roles);
  REQUIRE(m.roleJoint == std::vector<std::int32_t>(roles.begin(), roles.end()));
  // Each role binds to the joint the annotation found for it.
  for (const auto& [role, joint] : std::vector<std::pair<std::string, int>>{
           {"left_fist", b.db.roles.fist[0]}, {"right_fist", b.db.roles.fist[1]}, {"left_wrist", b.db.roles.wrist[0]},
           {"right_forearm", b.db.roles.forearm[1]}, {"left_shoulder", b.db.roles.shoulder[0]},
           {"right_ankle", b.db.roles.ankle[1]}, {"left_toe", b.db.roles.toe[0]}, {"head", b.db.roles.head}}) {
    CAPTURE(role);
    BodyPoint point = parseBodyPoint(role);
    REQUIRE(bindBodyPoint(m, point, nullptr));
    CHECK(point.joint == joint);
  }
  const int pelvis = b.db.roles.pelvis, head = b.db.roles.head;
  const int leftFist = b.db.roles.fist[0], rightFist = b.db.roles.fist[1];
  double headHeight = 0;
  std::size_t sampled = 0;
  for (std::size_t i = 0; i < m.actionFrames.size(); i += 7, ++sampled) {
    CAPTURE(i);
    // The pelvis stands on the avatar frame's origin: its ground point is frameRoot's.
    const Eigen::Vector3d p = jointAt(m, i, pelvis);
    CHECK(p.x() == Approx(m.frameRoot[3 * i]).margin(1e-4));
    CHECK(p.z() == Approx(m.frameRoot[3 * i + 1]).margin(1e-4));
    headHeight += jointAt(m, i, head).y();
    // A rigid move: the fists are as far apart as in the capture at the frame played.
    const std::uint32_t v = m.actionFrames[i];
    const Clip& clip = b.db.clipAt(v);
    std::vector<Eigen::Quaterniond> rotations(skeleton.jointCount());
    std::vector<Eigen::Vector3d> positions(skeleton.jointCount());
    forwardKinematics(clip.motion, b.db.localFrame(v), rotations, positions);
    CHECK((jointAt(m, i, leftFist) - jointAt(m, i, rightFist)).norm() ==
          Approx((positions[leftFist] - positions[rightFist]).norm()).margin(1e-4));
    CHECK(jointAt(m, i, head).y() == Approx(positions[head].y() - clip.annotation.groundY).margin(1e-4));
  }
  // A standing boxer's head is at head height.
  CHECK(headHeight / static_cast<double>(sampled) > 1.3);
  CHECK(headHeight / static_cast<double>(sampled) < 1.9);
  // At an effective punch the fist joint is near the fist tip and moving fast.
  std::size_t hits = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a)
    for (const ActionHit& h : m.hitsOf(a)) {
      const std::size_t i = m.actionFrameBegin[a] + h.offset - 1;
      const int fist = h.hand == 0 ? leftFist : rightFist;
      CHECK((jointAt(m, i, fist) - Eigen::Vector3d(h.x, h.y, h.z)).norm() < 0.15);
      CHECK(m.sourceJointSpeed[m.actionFrames[i] * m.jointNames.size() + fist] > 1.0);
      ++hits;
    }
  CHECK(hits > 50);
}

TEST_CASE("a role overridden in the scenario is the joint a body point of that role measures", "[graph][data]") {
  const Boxing& b = boxing();
  std::vector<std::pair<std::string, Motion>> motions;
  for (const Clip& clip : b.db.clips) motions.emplace_back(clip.name, clip.motion);
  const MotionDatabase db = makeMotionDatabase(std::move(motions), RoleOverrides{{"head", "Neck"}});
  const StateActionModel m = buildStateActionModel(db, b.scenario.graph);
  BodyPoint head = parseBodyPoint("head"), neck = parseBodyPoint("Neck");
  REQUIRE(bindBodyPoint(m, head, nullptr));
  REQUIRE(bindBodyPoint(m, neck, nullptr));
  CHECK(head.joint == neck.joint);
  CHECK(m.jointNames[static_cast<std::size_t>(head.joint)] == "Neck");
  BodyPoint unchanged = parseBodyPoint("head");
  REQUIRE(bindBodyPoint(b.model, unchanged, nullptr));
  CHECK(b.model.jointNames[static_cast<std::size_t>(unchanged.joint)] == "Head");
}

TEST_CASE("the fast distance kernel agrees with the exact geodesic distance", "[graph][data]") {
  const Boxing& b = boxing();
  const FrameFeatures features = computeFrameFeatures(b.db, b.scenario.graph);
  const auto transitions = findTransitions(b.db, features, b.scenario.graph);
  REQUIRE(transitions.size() > 100);
  for (std::size_t t = 0; t < transitions.size(); t += 7) {
    const auto& c = transitions[t];
    CAPTURE(c.from, c.to);
    CHECK(c.distance == Approx(std::sqrt(frameDistance2(features, c.from, c.to - 1))).margin(2e-3));
    CHECK(c.distance < b.scenario.graph.threshold);
  }
}

TEST_CASE("without contact events, transitions are local minima of the distance matrix", "[graph][data]") {
  const Boxing& b = boxing();
  GraphParams params = b.scenario.graph;
  params.contactEvent = ContactEvent::None;
  params.threshold = 0.2;
  const FrameFeatures features = computeFrameFeatures(b.db, params);
  TransitionSearchStats stats;
  const auto transitions = findTransitions(b.db, features, params, &stats);
  REQUIRE(transitions.size() > 100);
  CHECK(stats.pairs >= std::size_t{1900} * 1900);
  for (std::size_t t = 0; t < transitions.size(); t += 13) {
    const std::uint32_t i = transitions[t].from, j = transitions[t].to - 1;
    const double d = frameDistance2(features, i, j);
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj) {
        const std::uint32_t a = i + di, c = j + dj;
        if ((di == 0 && dj == 0) || a >= b.db.frameCount() || c + 1 >= b.db.frameCount()) continue;
        if (b.db.clipOf(a) != b.db.clipOf(i) || b.db.clipOf(c) != b.db.clipOf(j)) continue;
        CAPTURE(i, j, di, dj);
        CHECK(d <= frameDistance2(features, a, c) + 2e-3);
      }
  }
}

TEST_CASE("the same input gives a byte-identical graph with any thread count", "[graph][data]") {
  const Boxing& b = boxing();
  GraphParams one = b.scenario.graph, two = b.scenario.graph;
  one.threads = 1;
  two.threads = 2;
  const StateActionModel m1 = buildStateActionModel(b.db, one);
  const StateActionModel m2 = buildStateActionModel(b.db, two);
  const auto dir = std::filesystem::temp_directory_path() / "mgrl_graph_identical";
  std::filesystem::remove_all(dir);
  saveGraphBundle(dir / "a", m1, {{"key", "k"}});
  saveGraphBundle(dir / "b", m2, {{"key", "k"}});
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "a")) {
    CAPTURE(entry.path().filename().string());
    CHECK(readFile(entry.path()) == readFile(dir / "b" / entry.path().filename()));
    ++files;
  }
  CHECK(files > 10);
  std::filesystem::remove_all(dir);
}

TEST_CASE("blended playback never jumps further than the capture and keeps feet planted", "[graph][data]") {
  const Boxing& b = boxing();
  const PlaybackCheck check = checkPlayback(b.db, b.model, b.scenario.graph.blendFrames, 300, 7);
  REQUIRE(check.transitions > 50);
  CHECK(check.maxJointStep_m <= check.sourceMaxJointStep_m + 1e-9);
  // Foot sliding no worse than the capture's own at the same frames (5 % noise allowed).
  CHECK(check.slide.meanSpeed_mps <= 1.05 * check.sourceSlideSameFrames_mps);
  // Without blending, transitions jump: the playback's worst step relative to the data grows.
  const PlaybackCheck raw = checkPlayback(b.db, b.model, 0, 300, 7);
  CHECK(raw.worstJointStepRatio > check.worstJointStepRatio);
}

TEST_CASE("locked feet stay where they landed while planted, with bones of constant length", "[graph][data]") {
  const Boxing& b = boxing();
  const Skeleton& skeleton = *b.db.skeleton;
  // Horizontal speeds over frame pairs with the foot planted in both, of the ankle, the toe
  // and the point the annotation rests the foot on (Annotation::footPivot: the ankle at 0,
  // the toe at 1), and the largest change of any bone's length, for a seeded random walk of
  // 300 actions.
  struct Walk {
    std::vector<double> ankle, toe, rest;
    double bone = 0;
  };
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  auto ninetieth = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() * 9 / 10];
  };
  auto walk = [&](bool lock) {
    ActionPlayback playback(b.db, b.model, b.scenario.graph.blendFrames, false);
    playback.setFootLock(lock);
    playback.reset(0);
    Rng rng(11);
    Pose pose;
    Walk w;
    std::vector<double> rest(skeleton.jointCount(), -1);
    std::array<Eigen::Vector3d, 2> ankleBefore{}, toeBefore{};
    std::array<bool, 2> wasDown{false, false};
    auto speed = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
      return std::hypot(to.x() - from.x(), to.z() - from.z()) / b.model.frameTime;
    };
    for (int n = 0; n < 300; ++n) {
      const std::uint32_t s = playback.state();
      const std::uint32_t begin = b.model.stateActionBegin[s];
      playback.begin(begin + static_cast<std::uint32_t>(rng.below(b.model.stateActionBegin[s + 1] - begin)));
      while (playback.next(pose)) {
        const auto positions = playback.positions();
        const std::uint32_t v = playback.frame();
        const std::size_t c = b.db.clipOf(v);
        const std::size_t k = v - b.db.offsets[c];
        for (std::size_t side = 0; side < 2; ++side) {
          const bool down = b.db.clips[c].annotation.contact[side][k] != 0;
          const Eigen::Vector3d ankle = positions[static_cast<std::size_t>(b.db.roles.ankle[side])];
          const Eigen::Vector3d toe = positions[static_cast<std::size_t>(b.db.roles.toe[side])];
          if (down && wasDown[side]) {
            const double pivot = b.db.clips[c].annotation.footPivot[side][k];
            w.ankle.push_back(speed(ankleBefore[side], ankle));
            w.toe.push_back(speed(toeBefore[side], toe));
            w.rest.push_back(speed(ankleBefore[side] + pivot * (toeBefore[side] - ankleBefore[side]),
                                   ankle + pivot * (toe - ankle)));
          }
          ankleBefore[side] = ankle;
          toeBefore[side] = toe;
          wasDown[side] = down;
        }
        for (std::size_t j = 1; j < skeleton.jointCount(); ++j) {
          const double length = (positions[j] - positions[static_cast<std::size_t>(skeleton.joint(j).parent)]).norm();
          if (rest[j] < 0) rest[j] = length;
          w.bone = std::max(w.bone, std::abs(length - rest[j]));
        }
      }
    }
    return w;
  };
  const Walk free = walk(false), locked = walk(true);
  INFO("planted speeds (m/s), median and 90th percentile: ankle free "
       << median(free.ankle) << ", " << ninetieth(free.ankle) << "; locked " << median(locked.ankle) << ", "
       << ninetieth(locked.ankle));
  INFO("toe free " << median(free.toe) << ", " << ninetieth(free.toe) << "; locked " << median(locked.toe) << ", "
                   << ninetieth(locked.toe));
  INFO("resting point free " << median(free.rest) << ", " << ninetieth(free.rest) << "; locked " << median(locked.rest)
                             << ", " << ninetieth(locked.rest));
  REQUIRE(free.ankle.size() == locked.ankle.size());  // the same walk
  REQUIRE(free.ankle.size() > 1000);
  // The point the foot rests on stays put (it would move when the body turned a foot past
  // its twist limit, in 1 frame pair of 10 at most).
  CHECK(median(locked.rest) < 1e-9);
  CHECK(ninetieth(locked.rest) < 1e-6);
  // Every foot joint slides less than the source motion played freely does, and at most
  // what the SNU sparring capture's feet do (ankles 0.078 m/s, toes 0.029).
  CHECK(median(locked.ankle) < 0.078);
  CHECK(median(locked.toe) < 0.029);
  CHECK(ninetieth(locked.ankle) < 0.5 * ninetieth(free.ankle));
  CHECK(ninetieth(locked.toe) < 0.5 * ninetieth(free.toe));
  CHECK(median(free.ankle) > 0.05);  // what the lock removes is there without it
  CHECK(median(free.toe) > 0.05);
  CHECK(locked.bone < 1e-6);
  CHECK(free.bone < 1e-6);
}

// The lock must let go: a foot that stayed pinned after lifting would keep planted ankles
// still too, so the test above, which looks at planted frames only, cannot see it. The lock
// turns only the locked leg's joints and never moves the root, so once a lifted foot's
// release is over its ankle is exactly where the same walk without the lock puts it.
// Plays `actions` seeded random actions on two playbacks in lock step (the same action
// from the same state each time), calling `frame(a, b)` after each frame both produced;
// `endTogether`: also require that `two` has no frame left when `one` ends an action.
template <typename Frame>
void walkInLockstep(const StateActionModel& model, ActionPlayback& one, ActionPlayback& two, Pose& a, Pose& b,
                    std::uint64_t seed, int actions, Frame frame, bool endTogether = false) {
  Rng rng(seed);
  for (int n = 0; n < actions; ++n) {
    const std::uint32_t s = one.state();
    REQUIRE(two.state() == s);
    const std::uint32_t begin = model.stateActionBegin[s];
    const auto action = begin + static_cast<std::uint32_t>(rng.below(model.stateActionBegin[s + 1] - begin));
    one.begin(action);
    two.begin(action);
    while (one.next(a)) {
      REQUIRE(two.next(b));
      frame(a, b);
    }
    if (endTogether) REQUIRE_FALSE(two.next(b));
  }
}

// Two playbacks of the boxing graph at state 0, the second with the foot lock on, for
// walkInLockstep.
struct FreeAndLocked {
  ActionPlayback unlocked, locked;
  explicit FreeAndLocked(const Boxing& b)
      : unlocked(b.db, b.model, b.scenario.graph.blendFrames, false),
        locked(b.db, b.model, b.scenario.graph.blendFrames, false) {
    locked.setFootLock(true);
    unlocked.reset(0);
    locked.reset(0);
  }
};

TEST_CASE("a locked foot follows the motion again once its contact ends", "[graph][data]") {
  const Boxing& b = boxing();
  FreeAndLocked walks(b);
  ActionPlayback &unlocked = walks.unlocked, &locked = walks.locked;
  // "Let go over a few frames when it lifts" (playback.hpp); foot_lock.cpp takes 4, so from
  // the 8th lifted frame on the lock must have no effect left.
  constexpr int kReleased = 8;
  Pose unlockedPose, lockedPose;
  std::array<int, 2> lifted{0, 0};  // per foot: frames since its contact ended (0 while down)
  std::size_t released = 0, pinnedFrames = 0;
  double worst = 0, lockedMoves = 0;
  std::array<Eigen::Vector3d, 2> lockedBefore{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  // Boxers keep their feet down most of the time: a long walk for enough lifted frames.
  walkInLockstep(b.model, unlocked, locked, unlockedPose, lockedPose, 11, 2000, [&](const Pose&, const Pose&) {
      const std::uint32_t v = unlocked.frame();
      const std::size_t c = b.db.clipOf(v);
      for (std::size_t side = 0; side < 2; ++side) {
        const bool down = b.db.clips[c].annotation.contact[side][v - b.db.offsets[c]] != 0;
        const auto ankle = static_cast<std::size_t>(b.db.roles.ankle[side]);
        const Eigen::Vector3d lockedAnkle = locked.positions()[ankle];
        lifted[side] = down ? 0 : lifted[side] + 1;
        if (lifted[side] >= kReleased) {
          const double gap = (lockedAnkle - unlocked.positions()[ankle]).norm();
          worst = std::max(worst, gap);
          ++released;
          // And the lifted foot moves as the capture does, rather than hanging in the air.
          const double step = std::hypot(lockedAnkle.x() - lockedBefore[side].x(), lockedAnkle.z() - lockedBefore[side].z());
          lockedMoves += step;
          pinnedFrames += step < 1e-6;
        }
        lockedBefore[side] = lockedAnkle;
      }
  });
  INFO(released << " lifted frames past the release; largest ankle gap to the unlocked walk " << worst << " m; "
                << pinnedFrames << " of them with the ankle still; mean step " << lockedMoves / static_cast<double>(released)
                << " m");
  REQUIRE(released > 500);
  CHECK(worst < 1e-9);
  CHECK(pinnedFrames < released / 10);
}

// A held foot keeps its heading while the body turns above it, but not without limit: a
// foot turned more than 25 degrees (foot_lock.cpp's kMaxFootTwist) away from the motion's
// heading pivots, as a hip can rotate only so far. Without the limit the legs would twist
// through each other in a long turn; without the heading kept, the toes would sweep about
// the ankle (the test above).
TEST_CASE("a held foot turns at most 25 degrees away from the motion's heading", "[graph][data]") {
  const Boxing& b = boxing();
  FreeAndLocked walks(b);
  ActionPlayback &unlocked = walks.unlocked, &locked = walks.locked;
  auto heading = [](const Eigen::Quaterniond& q) { return 2 * std::atan2(q.y(), q.w()); };
  Pose unlockedPose, lockedPose;
  double widest = 0;
  std::size_t planted = 0, turned = 0;
  walkInLockstep(b.model, unlocked, locked, unlockedPose, lockedPose, 5, 1000, [&](const Pose&, const Pose&) {
    const std::uint32_t v = unlocked.frame();
    const std::size_t c = b.db.clipOf(v);
    for (std::size_t side = 0; side < 2; ++side) {
      if (!b.db.clips[c].annotation.contact[side][v - b.db.offsets[c]]) continue;
      const auto ankle = static_cast<std::size_t>(b.db.roles.ankle[side]);
      const double apart = std::abs(std::remainder(
          heading(locked.globalRotations()[ankle]) - heading(unlocked.globalRotations()[ankle]), 2 * M_PI));
      widest = std::max(widest, apart);
      ++planted;
      turned += apart > 10 * M_PI / 180;
    }
  });
  INFO(planted << " planted foot-frames, " << turned << " of them held more than 10 degrees from the motion's heading; "
               << "widest " << widest * 180 / M_PI << " degrees");
  REQUIRE(planted > 5000);
  CHECK(turned > planted / 50);  // the lock does turn feet back
  // 25 degrees of heading, plus what half the motion's change of pitch and roll leaves of
  // the twist, with a degree of slack.
  CHECK(widest * 180 / M_PI < 26);
}

TEST_CASE("frames posed from the source poses are forward kinematics' poses", "[graph][data]") {
  const Boxing& b = boxing();
  const SourcePoses source = makeSourcePoses(b.db);
  REQUIRE(source.frameCount() == b.db.frameCount());
  // The same seeded walk (with transitions, blends, root shifts and foot locks) played twice:
  // forward kinematics on every frame, and the source poses outside blends.
  for (const auto& [lockFeetOption, footLockOption] : {std::pair{false, false}, std::pair{true, false}, std::pair{true, true}}) {
    // Copies: clang 14 does not let a lambda capture a structured binding (C++20 allows it).
    const bool lockFeet = lockFeetOption, footLock = footLockOption;
    ActionPlayback plain(b.db, b.model, b.scenario.graph.blendFrames, lockFeet),
        fast(b.db, b.model, b.scenario.graph.blendFrames, lockFeet);
    for (ActionPlayback* p : {&plain, &fast}) {
      p->setFootLock(footLock);
      p->reset(3, GroundMotion{1.5, -2.0, 0.7});
    }
    fast.setSourcePoses(&source);
    Pose a, c;
    std::size_t frames = 0;
    double worst = 0, worstRotation = 0;
    walkInLockstep(b.model, plain, fast, a, c, 5, 200, [&](const Pose&, const Pose&) {
        ++frames;
        // The pose itself (what is exported and streamed) is the same to the bit, unless the
        // root shift or a foot lock used positions that differ by rounding.
        if (!lockFeet && !footLock) {
          REQUIRE(a.rotations.size() == c.rotations.size());
          for (std::size_t j = 0; j < a.rotations.size(); ++j) {
            REQUIRE(a.rotations[j].coeffs() == c.rotations[j].coeffs());
            REQUIRE(a.translations[j] == c.translations[j]);
          }
        }
        for (std::size_t j = 0; j < a.rotations.size(); ++j) {
          worstRotation = std::max(worstRotation, (a.rotations[j].coeffs() - c.rotations[j].coeffs()).norm());
          worst = std::max(worst, (a.translations[j] - c.translations[j]).norm());
        }
        for (std::size_t j = 0; j < a.rotations.size(); ++j) {
          worst = std::max(worst, (plain.positions()[j] - fast.positions()[j]).norm());
          worstRotation = std::max(worstRotation,
                                   (plain.globalRotations()[j].coeffs() - fast.globalRotations()[j].coeffs()).norm());
        }
    }, /*endTogether=*/true);
    INFO("lockFeet " << lockFeet << ", footLock " << footLock << ": " << frames << " frames; largest difference " << worst << " m, "
                     << worstRotation << " in a quaternion");
    CHECK(frames > 2000);
    CHECK(worst < 1e-9);
    CHECK(worstRotation < 1e-9);
    CHECK(plain.world().dx == Approx(fast.world().dx).margin(1e-9));
    CHECK(plain.world().dyaw == Approx(fast.world().dyaw).margin(1e-9));
  }
  // A pose's constant offsets are written once, and again when its owner says they changed.
  ActionPlayback playback(b.db, b.model, 4);
  playback.reset(0);
  playback.begin(b.model.stateActionBegin[0]);
  Pose pose;
  REQUIRE(playback.next(pose));
  REQUIRE(pose.offsetsOf == b.db.skeleton->id());
  const std::size_t last = b.db.skeleton->jointCount() - 1;
  REQUIRE(b.db.skeleton->translationSlot(last) < 0);
  CHECK(pose.translations[last] == b.db.skeleton->joint(last).offset);
  pose.translations[last] = Eigen::Vector3d(9, 9, 9);
  pose.offsetsOf = 0;
  REQUIRE(playback.next(pose));
  CHECK(pose.translations[last] == b.db.skeleton->joint(last).offset);
  // The same pose played by a skeleton of as many joints but other offsets takes them.
  MotionDatabase larger = b.db;
  larger.skeleton = std::make_shared<const Skeleton>(b.db.skeleton->scaled(2));
  ActionPlayback other(larger, b.model, 4);
  other.reset(0);
  other.begin(b.model.stateActionBegin[0]);
  REQUIRE(other.next(pose));
  CHECK(pose.offsetsOf == larger.skeleton->id());
  CHECK(pose.translations[last] == 2 * b.db.skeleton->joint(last).offset);
  // Ids name contents, not addresses: a copy keeps its original's, a skeleton built in the
  // storage of another gets a new one.
  CHECK(Skeleton(*b.db.skeleton).id() == b.db.skeleton->id());
  std::optional<Skeleton> slot(std::in_place, b.db.skeleton->scaled(1));
  const Skeleton* address = &*slot;
  const std::uint64_t first = slot->id();
  slot.emplace(b.db.skeleton->scaled(3));
  REQUIRE(&*slot == address);
  CHECK(slot->id() != first);
  CHECK(slot->id() != b.db.skeleton->id());
  SourcePoses wrong = source;
  wrong.height.pop_back();
  REQUIRE_THROWS_WITH(playback.setSourcePoses(&wrong),
                      Catch::Contains(fmt::format("playback: expected source poses of {} frames", b.db.frameCount())));
  wrong = source;
  wrong.positions.pop_back();  // the frame count right, one array short
  REQUIRE_THROWS_WITH(playback.setSourcePoses(&wrong),
                      Catch::Contains(fmt::format("{} positions", source.positions.size() - 1)));
}

TEST_CASE("playback refuses an action that does not leave the current state", "[graph][data]") {
  const Boxing& b = boxing();
  ActionPlayback playback(b.db, b.model, 4);
  playback.reset(0);
  std::vector<Pose> poses;
  const std::uint32_t foreign = b.model.stateActionBegin[1];
  REQUIRE_THROWS_WITH(playback.play(foreign, poses), Catch::Contains("expected an action leaving state 0"));
  playback.play(b.model.stateActionBegin[0], poses);
  CHECK(poses.size() == b.model.actionLength(b.model.stateActionBegin[0]));
  CHECK(playback.state() == b.model.actionTo[b.model.stateActionBegin[0]]);
}

TEST_CASE("playback refuses a state that does not exist", "[graph][data]") {
  const Boxing& b = boxing();
  ActionPlayback playback(b.db, b.model, 4);
  const auto states = static_cast<std::uint32_t>(b.model.stateCount());
  REQUIRE_THROWS_WITH(playback.reset(states),
                      Catch::Contains(fmt::format("playback: expected a state below {}, found {}", states, states)));
}

TEST_CASE("graph parameters out of range name their YAML key", "[graph]") {
  GraphParams params;
  REQUIRE_NOTHROW(params.validate());
  params.threshold = 0;
  REQUIRE_THROWS_WITH(params.validate(), Catch::Contains("graph.threshold: expected a distance in (0, 10], found 0"));
  params = {};
  params.blendFrames = -1;
  REQUIRE_THROWS_WITH(params.validate(),
                      Catch::Contains("graph.blend_frames: expected a frame count in [0, 120], found -1"));
  params = {};
  params.jointWeights["Spine"] = -1;
  REQUIRE_THROWS_WITH(params.validate(),
                      Catch::Contains("graph.joint_weights.Spine: expected a weight in [0, 100], found -1"));
}

namespace {

// The Bandai Namco library (18 minutes in 174 clips) whose names start with one of `prefixes`
// (all when empty), loaded as a scenario loads them.
MotionDatabase library(const std::vector<std::string>& prefixes = {}) {
  const std::filesystem::path folder = test::mocap() / "bandai_namco_1" / "data";
  MotionSpec spec;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    const bool wanted = prefixes.empty() || std::any_of(prefixes.begin(), prefixes.end(), [&](const std::string& p) {
                          return name.rfind("dataset-1_" + p + "_", 0) == 0;
                        });
    if (wanted && entry.path().extension() == ".bvh") spec.files.push_back(entry.path());
  }
  std::sort(spec.files.begin(), spec.files.end());
  REQUIRE_FALSE(spec.files.empty());
  return loadMotionDatabase(spec);
}

// Out-edges (actions) per state.
std::vector<std::uint32_t> outDegrees(const StateActionModel& m) {
  std::vector<std::uint32_t> degree;
  for (std::size_t s = 0; s < m.stateCount(); ++s) degree.push_back(m.stateActionBegin[s + 1] - m.stateActionBegin[s]);
  return degree;
}

}  // namespace

TEST_CASE("max_out_degree keeps each frame's nearest transitions and the whole component", "[graph][data]") {
  const MotionDatabase db = library();
  GraphParams params;
  params.threshold = 0.6;
  params.contactEvent = ContactEvent::AnyContactChange;
  params.standingCuts = false;
  params.maxOutDegree = 0;
  const StateActionModel all = buildStateActionModel(db, params);
  params.maxOutDegree = 12;
  GraphBuildReport report;
  const StateActionModel bounded = buildStateActionModel(db, params, &report);
  INFO(fmt::format("{} actions in {} states unbounded, {} in {} bounded; {} left out, {} put back in {} rounds",
                   all.actionCount(), all.stateCount(), bounded.actionCount(), bounded.stateCount(),
                   report.transitionsPruned + report.transitionsRestored, report.transitionsRestored,
                   report.repairRounds));
  // The same frames in the component: the bound never costs the graph a clip.
  CHECK(bounded.componentFrames == all.componentFrames);
  CHECK(report.outDegreeBound == 12);
  CHECK(report.transitionsPruned > 0);
  CHECK(bounded.actionCount() < all.actionCount() / 2);
  CHECK(bounded.transitionDistance.size() + report.transitionsPruned == all.transitionDistance.size());
  // Only frames that needed a transition back exceed the bound, each by the few put back.
  const std::vector<std::uint32_t> degree = outDegrees(bounded);
  std::size_t over = 0;
  for (std::uint32_t d : degree) over += d > 12 ? d - 12 : 0;
  CHECK(over <= report.transitionsRestored);
  // A frame within its bound kept its smallest-distance transitions of the unbounded graph.
  auto transitionsOf = [](const StateActionModel& m) {
    std::map<std::uint32_t, std::vector<float>> byFrame;
    for (std::size_t t = 0; t < m.transitionDistance.size(); ++t)
      byFrame[m.transitions[2 * t]].push_back(m.transitionDistance[t]);
    for (auto& [frame, list] : byFrame) std::sort(list.begin(), list.end());
    return byFrame;
  };
  const auto before = transitionsOf(all), after = transitionsOf(bounded);
  std::size_t checked = 0;
  for (const auto& [frame, kept] : after) {
    if (kept.size() >= 12) continue;  // possibly repaired
    const std::vector<float>& candidates = before.at(frame);
    REQUIRE(kept.size() <= candidates.size());
    CHECK(std::equal(kept.begin(), kept.end(), candidates.begin()));
    ++checked;
  }
  CHECK(checked > 100);
  REQUIRE_NOTHROW(checkModel(bounded, "bounded"));
}

TEST_CASE("standing cuts join the clips where the performer stands still", "[graph][data]") {
  // Gestures (bows, waves, guiding) stand in place: no foot lifts off to cut them at.
  const MotionDatabase db = library({"bow", "bye", "guide", "walk"});
  FrameFeatures features = computeFrameFeatures(db, GraphParams{});
  const std::vector<std::uint32_t> cuts = standingCutFrames(db, features);
  REQUIRE(cuts.size() > 50);
  const auto half = static_cast<std::uint32_t>(std::lround(GraphParams::kStandingCutSpacing_s / db.frameTime));
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    const std::size_t c = db.clipOf(cuts[i]);
    const std::uint32_t k = cuts[i] - db.offsets[c];
    CHECK(db.clips[c].annotation.contact[0][k]);
    CHECK(db.clips[c].annotation.contact[1][k]);
    if (i > 0 && db.clipOf(cuts[i - 1]) == c) CHECK(cuts[i] - cuts[i - 1] > half);
  }
  GraphParams params;
  params.threshold = 0.6;
  params.contactEvent = ContactEvent::AnyContactChange;
  params.minStates = 1;
  auto gestureShare = [&](bool standing) {
    params.standingCuts = standing;
    GraphBuildReport report;
    const StateActionModel m = buildStateActionModel(db, params, &report);
    CHECK(report.search.standingCutFrames == (standing ? report.search.standingCutFrames : 0));
    std::size_t inside = 0, total = 0;
    std::vector<std::uint8_t> in(db.frameCount(), 0);
    for (std::uint32_t f : m.componentFrames) in[f] = 1;
    for (std::size_t c = 0; c < db.clips.size(); ++c) {
      if (db.clips[c].name.find("_walk") != std::string::npos) continue;
      for (std::uint32_t f = db.offsets[c]; f < db.offsets[c + 1]; ++f) inside += in[f];
      total += db.offsets[c + 1] - db.offsets[c];
    }
    return static_cast<double>(inside) / static_cast<double>(total);
  };
  const double without = gestureShare(false), with = gestureShare(true);
  WARN(fmt::format("gesture frames in the component: {:.0f} % without standing cuts, {:.0f} % with", 100 * without,
                   100 * with));
  CHECK(with >= without + 0.2);
  CHECK(with >= 0.8);
}

TEST_CASE("auto bounds and cuts only a library: the paper's scenarios are built as before", "[graph][data]") {
  GraphParams params;
  CHECK(params.outDegreeFor(65) == 0);
  CHECK_FALSE(params.standingCutsFor(65));
  CHECK(params.outDegreeFor(GraphParams::kLibrarySeconds + 1) == GraphParams::kLibraryOutDegree);
  CHECK(params.standingCutsFor(GraphParams::kLibrarySeconds + 1));
  params.maxOutDegree = 0;
  params.standingCuts = false;
  CHECK(params.outDegreeFor(1e6) == 0);
  CHECK_FALSE(params.standingCutsFor(1e6));
  const Boxing& b = boxing();
  CHECK(b.report.outDegreeBound == 0);
  CHECK(b.report.search.standingCutFrames == 0);
  GraphParams on = b.scenario.graph;
  on.maxOutDegree = 4;
  on.standingCuts = true;
  GraphBuildReport report;
  const StateActionModel m = buildStateActionModel(b.db, on, &report);
  CHECK(report.search.standingCutFrames > 0);
  CHECK(m.actionCount() < b.model.actionCount());
}

TEST_CASE("the sparring scenario builds a graph over all SNU sparring tracks", "[graph][data]") {
  const Scenario s = loadScenario(scenarioFile("sparring"), test::mocap());
  REQUIRE(s.motion.files.size() == 20);
  const MotionDatabase db = loadMotionDatabase(s.motion);
  CHECK(db.frameCount() > 12000);
  const StateActionModel m = buildStateActionModel(db, s.graph);
  CHECK(m.stateCount() >= 100);
  CHECK(m.actionCount() >= 1000);
  CHECK(m.componentFrames.size() >= db.frameCount() / 2);
  REQUIRE_NOTHROW(checkModel(m, "sparring"));
}

TEST_CASE("a component too small to learn on is an error naming the parameter to relax", "[graph][data]") {
  const Boxing& b = boxing();
  GraphParams params = b.scenario.graph;
  params.threshold = 0.05;
  REQUIRE_THROWS_WITH(buildStateActionModel(b.db, params),
                      Catch::Contains("expected at least graph.min_states = 10") &&
                          Catch::Contains("raise graph.threshold (now 0.05)"));
}

TEST_CASE("a too-small component advises only contact events looser than the one in use", "[graph][data]") {
  const Boxing& b = boxing();
  GraphParams params = b.scenario.graph;
  params.threshold = 0.05;
  params.contactEvent = ContactEvent::LeftFootLiftoff;
  REQUIRE_THROWS_WITH(buildStateActionModel(b.db, params),
                      Catch::Contains("use graph.contact_event: any_contact_change or none, or add motion files"));
  params.contactEvent = ContactEvent::AnyContactChange;
  REQUIRE_THROWS_WITH(buildStateActionModel(b.db, params),
                      Catch::Contains("use graph.contact_event: none, or add motion files") &&
                          !Catch::Contains("any_contact_change or"));
  params.contactEvent = ContactEvent::None;
  REQUIRE_THROWS_WITH(buildStateActionModel(b.db, params),
                      Catch::Contains("raise graph.threshold (now 0.05), or add motion files") &&
                          !Catch::Contains("use graph.contact_event"));
}

TEST_CASE("files with different skeletons cannot share a graph", "[graph][data]") {
  MotionSpec spec;
  spec.files = {test::mocap() / "cmu/bvh/13_17_boxing.bvh", test::mocap() / "snu_martial_arts/motion/s_001_3_1.bvh"};
  REQUIRE_THROWS_WITH(loadMotionDatabase(spec), Catch::Contains("13_17_boxing.bvh and s_001_3_1.bvh have different "
                                                                "skeletons: expected 31 joints, found 22"));
  spec.files.clear();
  REQUIRE_THROWS_WITH(loadMotionDatabase(spec), Catch::Contains("expected at least one motion file, found none"));
}

TEST_CASE("clips of one graph need one frame rate and one body", "[graph][data]") {
  const Motion at30 = test::loadMocap("cmu/bvh/13_18_boxing.bvh", [] {
                        LoadOptions o;
                        o.fps = 30;
                        return o;
                      }()).motion;
  const Motion at60 = resample(at30, 60);
  REQUIRE_THROWS_WITH(makeMotionDatabase({{"a.bvh", at30}, {"b.bvh", at60}}),
                      Catch::Contains("b.bvh: expected 30 fps like a.bvh, found 60 fps"));
  // Motions for a scenario's files: one per file, each clip then named by its file.
  MotionSpec spec;
  spec.files = {"x/a.bvh", "x/b.bvh"};
  REQUIRE_THROWS_WITH(makeMotionDatabase({{"a.bvh", at30}}, spec),
                      Catch::Contains("motion.files: expected one motion per file (2), found 1"));
  const MotionDatabase two = makeMotionDatabase({{"a.bvh", at30}, {"b.bvh", at30}}, spec);
  CHECK(two.clips[1].path == std::filesystem::path("x/b.bvh"));
  REQUIRE_THROWS_WITH(makeMotionDatabase({{"a.bvh", at30}, {"big.bvh", at30.scaled(1.2)}}),
                      Catch::Contains("a.bvh and big.bvh have different skeletons: bone") &&
                          Catch::Contains("(more than 5 % apart)"));
  // Same joint count, one joint renamed.
  std::vector<std::string> names = test::humanoidNames();
  auto still = [](std::vector<std::string> jointNames) {
    auto skeleton = std::make_shared<const Skeleton>(test::humanoid(jointNames));
    const std::size_t n = skeleton->jointCount();
    return Motion(skeleton, 1.0 / 30, std::vector<Eigen::Quaterniond>(2 * n, Eigen::Quaterniond::Identity()),
                  std::vector<Eigen::Vector3d>(2 * skeleton->translatedJoints().size(), Eigen::Vector3d(0, 1, 0)));
  };
  const std::string renamed = names[1];
  names[1] = "Torso";
  REQUIRE_THROWS_WITH(makeMotionDatabase({{"a.bvh", still(test::humanoidNames())}, {"b.bvh", still(names)}}),
                      Catch::Contains(fmt::format("a.bvh and b.bvh have different skeletons: joint 1 is '{}' (parent 0) "
                                                  "in the first, 'Torso' (parent 0) in the second",
                                                  renamed)));
}

TEST_CASE("graph.joint_weights must name joints of the skeleton", "[graph][data]") {
  const Boxing& b = boxing();
  GraphParams params = b.scenario.graph;
  params.jointWeights["LeftElbow"] = 1;
  REQUIRE_THROWS_WITH(computeFrameFeatures(b.db, params),
                      Catch::Contains("graph.joint_weights: expected a joint of the skeleton") &&
                          Catch::Contains("found 'LeftElbow'"));
}

}  // namespace motion_graph_test
