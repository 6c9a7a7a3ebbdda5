#include <algorithm>
#include <cmath>
#include <filesystem>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace annotation_test {

using namespace mgrl;

namespace {

Annotation annotateFile(const std::string& file, double fps = 0) {
  LoadOptions options;
  options.fps = fps;
  const Motion m = test::loadMocap(file, options).motion;
  return annotate(m, findRoles(m.skeleton()));
}

double hitsPerSecond(const Annotation& a, double duration) { return static_cast<double>(a.hits.size()) / duration; }

// The humanoid standing still except for its pelvis height, which follows `heights`.
Motion bobbing(const std::vector<double>& heights, double fps) {
  auto skeleton = std::make_shared<const Skeleton>([] {
    Skeleton s = test::humanoid(test::humanoidNames());
    std::vector<Joint> joints(s.joints().begin(), s.joints().end());
    joints[0].channels = {{Channel::Kind::Position, Axis::X}, {Channel::Kind::Position, Axis::Y},
                          {Channel::Kind::Position, Axis::Z}};
    return Skeleton(joints);
  }());
  std::vector<Eigen::Quaterniond> rotations(heights.size() * skeleton->jointCount(), Eigen::Quaterniond::Identity());
  std::vector<Eigen::Vector3d> translations;
  for (double h : heights) translations.emplace_back(0, 1 + h, 0);
  return Motion(skeleton, 1.0 / fps, rotations, translations);
}

int transitions(const std::vector<std::uint8_t>& flags) {
  int count = 0;
  for (std::size_t f = 1; f < flags.size(); ++f) count += flags[f] != flags[f - 1];
  return count;
}

}  // namespace

TEST_CASE("boxing yields many effective hits at punch speeds, walking few or none", "[annotation][data]") {
  for (const char* file : {"cmu/bvh/13_17_boxing.bvh", "cmu/bvh/13_18_boxing.bvh"}) {
    CAPTURE(file);
    const Annotation a = annotateFile(file);
    CHECK(a.hits.size() >= 200);
    CHECK(a.punches[0] + a.punches[1] >= 20);
    CHECK(a.punches[0] >= 5);
    CHECK(a.punches[1] >= 5);
    std::vector<double> speeds;
    for (const EffectiveHit& h : a.hits) speeds.push_back(h.speed_mps);
    std::sort(speeds.begin(), speeds.end());
    const double peak = speeds.back(), median = speeds[speeds.size() / 2];
    INFO("median hit speed " << median << " m/s, peak " << peak << " m/s");
    CHECK(median >= 3.0);
    CHECK(peak >= 6.0);
    CHECK(peak <= 12.0);
    // Effective hitting points lie in front of the boxer, between hip and head height.
    const auto inFront = std::count_if(a.hits.begin(), a.hits.end(), [](const EffectiveHit& h) {
      return h.tipAvatar.z() > 0 && h.tipAvatar.y() > 0.5 && h.tipAvatar.y() < 1.9;
    });
    CHECK(static_cast<double>(inFront) >= 0.9 * static_cast<double>(a.hits.size()));
  }
  const double boxingRate = hitsPerSecond(annotateFile("cmu/bvh/13_17_boxing.bvh"), 4840 / 120.0);
  for (const char* file : {"cmu/bvh/02_02_walk.bvh", "cmu/bvh/07_05_walk.bvh"}) {
    CAPTURE(file);
    const Annotation a = annotateFile(file);
    CHECK(a.hits.size() <= 10);
    CHECK(a.punches[0] + a.punches[1] <= 5);
    CHECK(hitsPerSecond(a, 2.0) < 0.5 * boxingRate);
  }
}

TEST_CASE("the hit count scales with the frame rate, the punch count does not", "[annotation][data]") {
  const Annotation full = annotateFile("cmu/bvh/13_17_boxing.bvh");
  const Annotation low = annotateFile("cmu/bvh/13_17_boxing.bvh", 15);
  const double ratio = static_cast<double>(full.hits.size()) / static_cast<double>(low.hits.size());
  CHECK(ratio == Approx(8.0).epsilon(0.35));
  CHECK(std::abs((full.punches[0] + full.punches[1]) - (low.punches[0] + low.punches[1])) <= 8);
}

TEST_CASE("in walking, left and right foot contacts alternate", "[annotation][data]") {
  for (const char* file : {"cmu/bvh/07_05_walk.bvh", "cmu/bvh/02_02_walk.bvh"}) {
    CAPTURE(file);
    const Annotation a = annotateFile(file);
    // Touch-downs (contact starts) in time order must alternate sides.
    std::vector<std::pair<std::size_t, int>> touchdowns;
    for (int s = 0; s < 2; ++s)
      for (std::size_t f = 1; f < a.contact[s].size(); ++f)
        if (a.contact[s][f] && !a.contact[s][f - 1]) touchdowns.emplace_back(f, s);
    std::sort(touchdowns.begin(), touchdowns.end());
    REQUIRE(touchdowns.size() >= 3);
    for (std::size_t i = 1; i < touchdowns.size(); ++i) {
      CAPTURE(touchdowns[i].first);
      CHECK(touchdowns[i].second != touchdowns[i - 1].second);
    }
    // A walker always has a foot down.
    std::size_t supported = 0;
    for (std::size_t f = 0; f < a.contact[0].size(); ++f) supported += a.contact[0][f] || a.contact[1][f];
    CHECK(static_cast<double>(supported) >= 0.95 * static_cast<double>(a.contact[0].size()));
  }
}

TEST_CASE("foot contacts do not flicker when the foot hovers between the thresholds", "[annotation]") {
  // 40 planted frames, a slow rise, then 60 frames alternating 6.5 and 7.2 cm up (between
  // the 5 cm enter and 8 cm exit thresholds, and slow: the central difference of an
  // alternation is 0), then lifted for good (the last hovering frame already moves fast).
  std::vector<double> heights(40, 0.0);
  for (int i = 1; i <= 13; ++i) heights.push_back(0.005 * i);
  for (int i = 0; i < 61; ++i) heights.push_back(i % 2 ? 0.065 : 0.072);
  for (int i = 0; i < 40; ++i) heights.push_back(0.3);
  const Motion m = bobbing(heights, 120);
  const Annotation a = annotate(m, findRoles(m.skeleton()));
  for (int s = 0; s < 2; ++s) {
    CHECK(std::all_of(a.contact[s].begin(), a.contact[s].begin() + 113, [](auto c) { return c == 1; }));
    CHECK(transitions(a.contact[s]) == 1);
  }
  // Coming from above, the same hovering never enters contact.
  std::vector<double> fromAbove(40, 0.3);
  for (int i = 0; i < 60; ++i) fromAbove.push_back(i % 2 ? 0.065 : 0.072);
  for (int i = 0; i < 40; ++i) fromAbove.push_back(0.0);
  const Motion n = bobbing(fromAbove, 120);
  const Annotation b = annotate(n, findRoles(n.skeleton()));
  CHECK(std::none_of(b.contact[0].begin(), b.contact[0].begin() + 100, [](auto c) { return c == 1; }));
  CHECK(transitions(b.contact[0]) == 1);
}

// The humanoid standing, its left foot pitched by `pitch[f]` radians about the ankle's x
// (positive: the toe down, the heel up) and the body raised so that the toe stays at the
// floor when the pitch is positive; a negative pitch lifts the toe off a still ankle.
Motion rollingFoot(const std::vector<double>& pitch, double fps) {
  auto skeleton = std::make_shared<const Skeleton>([] {
    Skeleton s = test::humanoid(test::humanoidNames());
    std::vector<Joint> joints(s.joints().begin(), s.joints().end());
    joints[0].channels = {
        {Channel::Kind::Position, Axis::X}, {Channel::Kind::Position, Axis::Y}, {Channel::Kind::Position, Axis::Z}};
    return Skeleton(joints);
  }());
  const std::size_t joints = skeleton->jointCount(), ankle = 8;  // LeftFoot (test_support.cpp)
  REQUIRE(skeleton->joint(ankle).name == "LeftFoot");
  const Eigen::Vector3d toe = skeleton->joint(ankle + 1).offset;
  std::vector<Eigen::Quaterniond> rotations(pitch.size() * joints, Eigen::Quaterniond::Identity());
  std::vector<Eigen::Vector3d> translations;
  for (std::size_t f = 0; f < pitch.size(); ++f) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(pitch[f], Eigen::Vector3d::UnitX()));
    rotations[f * joints + ankle] = q;
    const double drop = toe.y() - (q * toe).y();  // how much lower the toe is than at rest
    translations.emplace_back(0, 1 + std::max(0.0, drop), 0);
  }
  return Motion(skeleton, 1.0 / fps, rotations, translations);
}

TEST_CASE("footPivot says which part of the foot it rests on: flat, on the ball, on the heel", "[annotation]") {
  // 1.3 s flat, 0.3 s on the ball (heel 5 cm up), 1.3 s flat, 0.3 s on the heel (toe 7 cm
  // up), 1.3 s flat, at 30 fps: short enough that each foot joint's planted level (its 10th
  // percentile within +-1 s) stays the flat foot's.
  const double up = 30 * M_PI / 180;
  std::vector<double> pitch(40, 0.0);
  pitch.insert(pitch.end(), 9, up);
  pitch.insert(pitch.end(), 40, 0.0);
  pitch.insert(pitch.end(), 9, -up);
  pitch.insert(pitch.end(), 40, 0.0);
  const Motion m = rollingFoot(pitch, 30);
  const Annotation a = annotate(m, findRoles(m.skeleton()));
  const std::vector<float>& left = a.footPivot[0];
  REQUIRE(left.size() == pitch.size());
  REQUIRE(a.footPivot[1].size() == pitch.size());
  for (std::size_t f = 0; f < pitch.size(); ++f) {
    CAPTURE(f, pitch[f]);
    if (pitch[f] > 0)
      CHECK(left[f] == 1.0f);  // on the ball
    else if (pitch[f] < 0)
      CHECK(left[f] == 0.0f);  // on the heel
    else
      CHECK(left[f] == Approx(0.5).margin(1e-6));  // flat
  }
}

TEST_CASE("a capture glitch in the hand is not an effective hit", "[annotation][data]") {
  // SNU 16_28_1 has a one-frame right-hand jump of about 23 m/s at frames 1-2 (DATA.md).
  const Annotation a = annotateFile("snu_martial_arts/motion/16_28_1.bvh");
  CHECK(a.glitchFrames >= 1);
  CHECK(std::none_of(a.hits.begin(), a.hits.end(), [](const EffectiveHit& h) { return h.frame <= 3; }));
}

TEST_CASE("floor-dipping frames do not drag the ground estimate down", "[annotation][data]") {
  // s_019_2_1 dips to -27 cm in places; the floor is still near 0.
  const Annotation a = annotateFile("snu_martial_arts/motion/s_019_2_1.bvh");
  CHECK(a.groundY == Approx(0.0).margin(0.04));
}

TEST_CASE("annotation thresholds are validated", "[annotation]") {
  AnnotationParams p;
  p.punchMinSpeed_mps = -1;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("punch_min_speed_mps"));
  p = {};
  p.contactHeightExit_m = 0.01;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("hysteresis"));
  p = {};
  p.punchMinAlignment = 2;
  CHECK_THROWS_AS(p.validate(), Error);
  for (double ratio : {-0.1, 1.0, std::nan("")}) {
    CAPTURE(ratio);
    p = {};
    p.knockdownHeadRatio = ratio;
    CHECK_THROWS_WITH(p.validate(), Catch::Contains("knockdown_head_ratio: expected a value in [0, 1)"));
  }
  p = {};
  p.knockdownHeadRatio = 0;
  CHECK_NOTHROW(p.validate());
}

TEST_CASE("the standing height comes from the motion's standing frames, not the rest pose", "[annotation]") {
  // boxer21.bvh stands with flat feet (ankles turned 60 degrees) though its rest pose
  // points the toes down: standing, the head top is 162.8 cm above the toe tips; the rest
  // pose says 175.2 cm.
  const Motion m = loadMotion(test::testData() / "boxer21.bvh").motion;
  const SkeletonRoles roles = findRoles(m.skeleton());
  const Annotation a = annotate(m, roles);
  CHECK(roles.restHeight == Approx(1.7516));
  CHECK(a.standingHeight == Approx(1.628).margin(0.002));
  CHECK(a.standingFrames > 0);
  CHECK(unusualHeightWarning(a, "boxer21.bvh").empty());

  // Half the size is no adult: a warning naming the file and the height.
  const Motion half = m.scaled(0.5);
  const Annotation small = annotate(half, findRoles(half.skeleton()));
  CHECK(small.standingHeight == Approx(0.81).margin(0.01));
  CHECK_THAT(unusualHeightWarning(small, "boxer21.bvh"),
             Catch::Contains("boxer21.bvh: standing height 0.81 m") && Catch::Contains("expected 1.2 to 2.2 m"));
}

TEST_CASE("standing heights of the real capture are the people's", "[annotation][data]") {
  // DATA.md: subject 13 is about 1.63 m; the rest pose gives 1.631.
  for (const char* file : {"cmu/bvh/13_17_boxing.bvh", "cmu/bvh/13_18_boxing.bvh"}) {
    CAPTURE(file);
    CHECK(annotateFile(file).standingHeight == Approx(1.63).margin(0.02));
  }
  // SNU's fighters: the rest pose (zero-length head end site continued by the neck) says 1.75.
  CHECK(annotateFile("snu_martial_arts/motion/s_001_3_1.bvh").standingHeight == Approx(1.75).margin(0.03));
  // No standing frame with both feet down in a run: one foot down will do.
  const Annotation run = annotateFile("cmu/bvh/09_06_run.bvh");
  CHECK(run.standingFrames > 0);
  CHECK(run.standingHeight == Approx(1.6).margin(0.08));
}

TEST_CASE("punches while knocked down are not effective", "[annotation]") {
  // boxer21.bvh throws the same left punch twice: standing (frames 15-27), then lying on
  // its back on the floor (frames 60-72), head top 12 cm above the floor.
  const Motion m = loadMotion(test::testData() / "boxer21.bvh").motion;
  const SkeletonRoles roles = findRoles(m.skeleton());
  const Annotation a = annotate(m, roles);
  CHECK(a.punches[0] == 1);
  CHECK(a.punches[1] == 0);
  CHECK(a.knockdownFrames == 45);
  REQUIRE(!a.hits.empty());
  CHECK(std::all_of(a.hits.begin(), a.hits.end(), [](const EffectiveHit& h) { return h.frame >= 15 && h.frame < 28; }));

  // With the rule off, the punch on the floor counts too: the arm motion is the same.
  AnnotationParams off;
  off.knockdownHeadRatio = 0;
  const Annotation b = annotate(m, roles, off);
  CHECK(b.punches[0] == 2);
  CHECK(b.knockdownFrames == 0);
  CHECK(std::any_of(b.hits.begin(), b.hits.end(), [](const EffectiveHit& h) { return h.frame >= 60; }));
}

TEST_CASE("no boxing punch is lost to the knockdown rule, SNU's take-downs are", "[annotation][data]") {
  for (const char* file : {"cmu/bvh/13_17_boxing.bvh", "cmu/bvh/135_06_martial_arts.bvh"}) {
    CAPTURE(file);
    CHECK(annotateFile(file).knockdownFrames == 0);
  }
  // s_001_3_1: one fighter is thrown about frame 332 and gets up about frame 470.
  const Annotation a = annotateFile("snu_martial_arts/motion/s_001_3_1.bvh");
  CHECK(a.knockdownFrames >= 100);
  CHECK(std::none_of(a.hits.begin(), a.hits.end(), [](const EffectiveHit& h) { return h.frame >= 340 && h.frame <= 460; }));
}

TEST_CASE("windowQuantiles gives each window's quantile exactly as a selection over the window would",
          "[annotation]") {
  std::uint32_t x = 7;
  auto next = [&] {
    x = x * 1664525u + 1013904223u;
    return static_cast<double>(x >> 26) * 0.25;  // 64 levels: many ties
  };
  for (std::size_t n : {0, 1, 2, 5, 61, 200}) {
    std::vector<double> values(n);
    for (double& v : values) v = next();
    for (std::size_t window : {0, 1, 3, 30, 500}) {
      for (double q : {0.0, 0.1, 0.5, 0.99, 1.0}) {
        CAPTURE(n, window, q);
        const std::vector<double> fast = mgrl::windowQuantiles(values, window, q);
        REQUIRE(fast.size() == n);
        for (std::size_t f = 0; f < n; ++f) {
          const std::size_t lo = f > window ? f - window : 0, hi = std::min(n, f + window + 1);
          std::vector<double> span(values.begin() + static_cast<std::ptrdiff_t>(lo),
                                   values.begin() + static_cast<std::ptrdiff_t>(hi));
          const auto k = static_cast<std::size_t>(q * static_cast<double>(span.size() - 1));
          std::nth_element(span.begin(), span.begin() + static_cast<std::ptrdiff_t>(k), span.end());
          REQUIRE(fast[f] == span[k]);
        }
      }
    }
  }
}

TEST_CASE("a plain front kick is found with the default kick settings, which count no kick in walks and runs",
          "[annotation]") {
  // kick.bvh: boxer21's body swings its straight left leg forward and up to 80 degrees in 6
  // frames (the toe tip at about 6 m/s) while the body steps forward and the ankle points
  // the toes: the toe tip's velocity is mostly across the shin (cosine 0.13 at best).
  const Motion m = loadMotion(test::testData() / "kick.bvh").motion;
  const SkeletonRoles roles = findRoles(m.skeleton());
  const Annotation a = annotate(m, roles);
  CHECK(a.kickCount[0] == 1);
  CHECK(a.kickCount[1] == 0);
  REQUIRE(!a.kicks.empty());
  CHECK(a.kicks.front().hand == Side::Left);
  CHECK(a.kicks.front().tipWorld.y() - a.groundY >= 0.3);
  CHECK(a.punches[0] + a.punches[1] == 0);
  // The defaults before (only kicks along the shin, from 3 m/s) missed it.
  AnnotationParams alongOnly;
  alongOnly.kickMinAlignment = 0.5;
  alongOnly.kickMinSpeed_mps = 3.0;
  CHECK(annotate(m, roles, alongOnly).kicks.empty());
}

TEST_CASE("walks and runs have no kicks and few punches with the default annotation", "[annotation][data]") {
  // Feet swing fast in a run but stay low; arms swing along the forearm but are carried by
  // the body, not driven out from it (punch_min_body_speed_mps).
  int punches = 0, swings = 0;
  for (const char* file : {"cmu/bvh/02_02_walk.bvh", "cmu/bvh/07_05_walk.bvh", "cmu/bvh/09_06_run.bvh"}) {
    CAPTURE(file);
    const Annotation a = annotateFile(file, 30);
    CHECK(a.kicks.empty());
    punches += a.punches[0] + a.punches[1];
    swings += a.swings[0] + a.swings[1];
  }
  CHECK(punches <= 3);
  CHECK(swings >= 3);
  // CMU's boxing keeps every punch: the test drops none of them.
  const Annotation boxing = annotateFile("cmu/bvh/13_17_boxing.bvh", 30);
  CHECK(boxing.swings[0] + boxing.swings[1] == 0);
  CHECK(boxing.punches[0] + boxing.punches[1] > 20);
}

TEST_CASE("a wrist standing in for the fist lowers the punch thresholds in proportion to its reach", "[annotation]") {
  // boxer21.bvh's wrists have 8 cm end sites past a 25 cm forearm: a fist's reach (1.32
  // forearms from the elbow, at least kFistReachPerForearm), thresholds as set. Without the
  // end sites the wrist itself is the tip, 1.0 forearm from the elbow: thresholds times 0.8.
  const Motion m = loadMotion(test::testData() / "boxer21.bvh").motion;
  const Annotation withTips = annotate(m, findRoles(m.skeleton()));
  CHECK(withTips.punchScale[0] == 1.0);
  CHECK(withTips.punchScale[1] == 1.0);

  std::vector<Joint> joints(m.skeleton().joints().begin(), m.skeleton().joints().end());
  for (Joint& j : joints)
    if (j.name == "LeftWrist" || j.name == "RightWrist") j.endSite.reset();
  auto bare = std::make_shared<const Skeleton>(joints);
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  for (std::size_t f = 0; f < m.frameCount(); ++f) {
    for (const Eigen::Quaterniond& q : m.rotations(f)) rotations.push_back(q);
    for (const Eigen::Vector3d& t : m.translations(f)) translations.push_back(t);
  }
  const Motion wrists(bare, m.frameTime(), rotations, translations);
  const Annotation a = annotate(wrists, findRoles(wrists.skeleton()));
  CHECK(a.punchScale[0] == Approx(1.0 / kFistReachPerForearm));
  CHECK(a.punchScale[1] == Approx(1.0 / kFistReachPerForearm));
  // Its one standing punch is still found, from the slower wrist.
  CHECK(a.punches[0] == 1);
}

// Precision and recall of `a`'s punches against the strikes labelled by hand in
// tests/data/labels/13_17_boxing_strikes.json (which says how they were labelled). A punch
// (a run of effective frames of one hand) matches a label of its hand whose peak frame lies
// from 2 frames before the run's start to 10 frames after its end (the fist is fastest
// before the arm is straight).
namespace {

struct LabelScore {
  std::size_t punches = 0, labels = 0;
  int found = 0, right = 0, wrong = 0;
  double recall = 0, precision = 0;
};
LabelScore scoreAgainstLabels(const Annotation& a, const nlohmann::json& labels) {
  struct Run {
    Side hand;
    std::uint32_t first, last;
  };
  std::vector<Run> runs;
  for (int s = 0; s < 2; ++s) {
    const auto side = static_cast<Side>(s);
    for (const EffectiveHit& h : a.hits) {
      if (h.hand != side) continue;
      if (!runs.empty() && runs.back().hand == side && runs.back().last + 1 == h.frame)
        runs.back().last = h.frame;
      else
        runs.push_back({side, h.frame, h.frame});
    }
  }
  auto matches = [](const Run& r, const nlohmann::json& label) {
    const Side side = label[0] == "left" ? Side::Left : Side::Right;
    const int frame = label[1];
    return r.hand == side && static_cast<int>(r.first) - 2 <= frame && frame <= static_cast<int>(r.last) + 10;
  };
  LabelScore score;
  score.punches = runs.size();
  score.labels = labels["strikes"].size();
  for (const nlohmann::json& label : labels["strikes"])
    score.found += std::any_of(runs.begin(), runs.end(), [&](const Run& r) { return matches(r, label); }) ? 1 : 0;
  for (const Run& r : runs) {
    const auto hit = [&](const nlohmann::json& list) {
      return std::any_of(list.begin(), list.end(), [&](const nlohmann::json& l) { return matches(r, l); });
    };
    if (hit(labels["strikes"]))
      ++score.right;
    else if (!hit(labels["unsure"]))
      ++score.wrong;
  }
  score.recall = static_cast<double>(score.found) / static_cast<double>(score.labels);
  score.precision = static_cast<double>(score.right) / std::max(1, score.right + score.wrong);
  return score;
}

nlohmann::json strikeLabels() {
  return nlohmann::json::parse(readFile(test::testData() / "labels" / "13_17_boxing_strikes.json"));
}

}  // namespace

TEST_CASE("effective punches against strikes labelled by hand in CMU 13_17: precision and recall", "[annotation][data]") {
  const nlohmann::json labels = strikeLabels();
  const LabelScore s = scoreAgainstLabels(annotateFile(labels["clip"], labels["fps"]), labels);
  WARN(fmt::format("CMU 13_17 at 30 fps: {} punches found; recall {:.2f} ({} of {} labelled strikes), precision {:.2f} "
                   "({} right, {} wrong, the rest on unsure labels)",
                   s.punches, s.recall, s.found, s.labels, s.precision, s.right, s.wrong));
  CHECK(s.recall >= 0.75);
  CHECK(s.precision >= 0.7);
}

// The punches of every file of a Bandai Namco category (the word after `dataset-1_`), loaded
// as a scenario loads them (the root motion moved from the file's static root to the hips).
namespace {
int libraryPunches(const std::string& category, const AnnotationParams& params) {
  const std::filesystem::path folder = test::mocap() / "bandai_namco_1" / "data";
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("dataset-1_" + category + "_", 0) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  REQUIRE_FALSE(names.empty());
  MotionSpec spec;
  for (const std::string& name : names) spec.files.push_back(folder / name);
  spec.annotation = params;
  int punches = 0;
  for (const Clip& clip : loadMotionDatabase(spec).clips)
    punches += clip.annotation.punches[0] + clip.annotation.punches[1];
  return punches;
}
}  // namespace

TEST_CASE(
    "swing_travel_mps: a library's walks, runs and dashes give no punches, its punch clips and CMU's boxing keep "
    "theirs",
    "[annotation][data]") {
  AnnotationParams library;
  library.swingTravel_mps = 0.9;
  // Arms pumping in 10 minutes of walks, runs and dashes: 231 punches by the other tests alone.
  int before = 0, after = 0;
  for (const char* category : {"walk", "walk-left", "walk-right", "walk-back", "run", "dash"}) {
    const int all = libraryPunches(category, AnnotationParams{});
    const int kept = libraryPunches(category, library);
    WARN(fmt::format("{}: {} punches, {} with swing_travel_mps 0.9", category, all, kept));
    before += all;
    after += kept;
  }
  CHECK(before > 200);
  CHECK(after <= 1);
  // The punch clips (thrown standing) keep every punch; so does the kick clips' count.
  CHECK(libraryPunches("punch", library) == libraryPunches("punch", AnnotationParams{}));
  CHECK(libraryPunches("punch", library) >= 8);
  // The reach exception: at a huge value no fast-travel run is excused; at 0 every one
  // whose fist moves away from the shoulder at all is (two thirds of the dashes' runs).
  AnnotationParams noExcuse = library;
  noExcuse.swingMaxReach_mps = 100;
  CHECK(libraryPunches("dash", noExcuse) == 0);
  AnnotationParams excuseAll = library;
  excuseAll.swingMaxReach_mps = 0;
  CHECK(libraryPunches("dash", excuseAll) > 50);

  // CMU's boxer stands: the same hits, the same recall against the hand labels.
  const nlohmann::json labels = strikeLabels();
  LoadOptions options;
  options.fps = labels["fps"];
  const Motion m = test::loadMocap(labels["clip"], options).motion;
  const Annotation plain = annotate(m, findRoles(m.skeleton()));
  const Annotation swung = annotate(m, findRoles(m.skeleton()), library);
  CHECK(swung.hits.size() == plain.hits.size());
  CHECK(scoreAgainstLabels(swung, labels).recall >= 0.8);
}

TEST_CASE("swing_travel_mps and swing_max_reach_mps out of range are refused by name", "[annotation]") {
  AnnotationParams p;
  p.swingTravel_mps = -1;
  CHECK_THROWS_WITH(p.validate(),
                    Catch::Contains("annotation: swing_travel_mps: expected a speed in [0, 20] m/s (0: off), "
                                    "found -1"));
  p.swingTravel_mps = 0.9;
  p.swingMaxReach_mps = std::nan("");
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("annotation: swing_max_reach_mps: expected a speed in [0, 100] m/s"));
}

TEST_CASE("punch_min_speed_mps: auto chooses a threshold from the capture's fist speeds that finds the labelled strikes",
          "[annotation][data]") {
  const nlohmann::json labels = strikeLabels();
  LoadOptions options;
  options.fps = labels["fps"];
  const Motion m = test::loadMocap(labels["clip"], options).motion;
  const SkeletonRoles roles = findRoles(m.skeleton());
  AnnotationParams params;
  params.punchMinSpeedAuto = true;
  const Motion* const one[] = {&m};
  const AutoPunchSpeed chosen = autoPunchMinSpeed(one, roles, params);
  INFO(chosen.sentence());
  CHECK_FALSE(chosen.fellBack);
  CHECK_FALSE(chosen.clamped);
  CHECK(chosen.samples >= 300);
  // The strikes' mode lies above it and the guard's below: between 1.5 and 2.3 m/s, where
  // the labelled strikes are found as well as at the default (a linear-scale split, 2.6 m/s,
  // would lose a tenth of them).
  CHECK(chosen.speed_mps > 1.5);
  CHECK(chosen.speed_mps < 2.3);
  CHECK_THAT(chosen.sentence(), Catch::Matches("punch threshold auto: [0-9.]+ m/s, the Otsu split of [0-9]+ fist speeds "
                                               "\\(log scale\\)"));
  // annotate() with auto is annotate() at the chosen speed.
  const Annotation automatic = annotate(m, roles, params);
  AnnotationParams fixed;
  fixed.punchMinSpeed_mps = chosen.speed_mps;
  const Annotation given = annotate(m, roles, fixed);
  CHECK(automatic.hits.size() == given.hits.size());
  CHECK(automatic.punches == given.punches);
  const LabelScore s = scoreAgainstLabels(automatic, labels);
  WARN(fmt::format("CMU 13_17 with auto ({:.2f} m/s): recall {:.2f}, precision {:.2f}", chosen.speed_mps, s.recall,
                   s.precision));
  CHECK(s.recall >= 0.75);
  CHECK(s.precision >= 0.7);
}

TEST_CASE("punch_min_speed_mps: auto keeps the default with too few fist speeds, and stays within its bounds",
          "[annotation]") {
  // The humanoid standing still: no fist moves, no sample.
  const Motion still = bobbing(std::vector<double>(60, 1.0), 30);
  AnnotationParams params;
  params.punchMinSpeedAuto = true;
  const Motion* const one[] = {&still};
  const AutoPunchSpeed chosen = autoPunchMinSpeed(one, findRoles(still.skeleton()), params);
  CHECK(chosen.fellBack);
  CHECK(chosen.samples == 0);
  CHECK(chosen.speed_mps == AnnotationParams{}.punchMinSpeed_mps);
  CHECK_THAT(chosen.sentence(), Catch::Contains("0 fist speeds are too few to choose from (expected at least 30)"));
  // No motion at all: the same.
  CHECK(autoPunchMinSpeed({}, findRoles(still.skeleton()), params).fellBack);
}

TEST_CASE("Otsu's threshold splits two groups between them and refuses a histogram it cannot make", "[annotation]") {
  std::vector<double> values;
  for (int i = 0; i < 100; ++i) values.push_back(1.0 + 0.002 * i);  // 1.0 .. 1.2
  for (int i = 0; i < 30; ++i) values.push_back(3.0 + 0.01 * i);    // 3.0 .. 3.3
  // Any edge in the empty gap between them splits them alike: the middle of the gap.
  const double t = otsuThreshold(values, 0, 4, 400);
  CHECK(t == Approx(2.1).margin(0.011));
  // Shifting the upper group moves the split with it (it is not a fixed point).
  for (int i = 100; i < 130; ++i) values[static_cast<std::size_t>(i)] += 0.5;
  CHECK(otsuThreshold(values, 0, 4, 400) > t);
  // One bin holds everything: nothing to split.
  CHECK(otsuThreshold(std::vector<double>(10, 2.0), 0, 4, 400) == 0);
  CHECK_THROWS_WITH(otsuThreshold(values, 1, 1, 400), Catch::Contains("expected at least 2 bins over lo < hi"));
  CHECK_THROWS_WITH(otsuThreshold(values, 0, 4, 1), Catch::Contains("found 1 over [0, 4]"));
}

}  // namespace annotation_test
