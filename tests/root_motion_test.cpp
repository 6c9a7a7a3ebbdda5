// Capture from other pipelines: a root that stays at the origin above the hips,
// takes that bake their start position into the hips, heads without a head top.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/motion/root_motion.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace root_motion_test {

using namespace mgrl;

namespace {

Motion loadTestFile(const char* name) { return loadMotion(test::testData() / name).motion; }

std::vector<std::pair<std::string, Motion>> clips(std::initializer_list<const char*> names) {
  std::vector<std::pair<std::string, Motion>> out;
  for (const char* name : names) out.emplace_back(name, loadTestFile(name));
  return out;
}

}  // namespace

TEST_CASE("a root that stays at the origin gives its motion to the hips below it", "[motion][root_motion]") {
  // root_at_origin.bvh: a 'Root' joint that never moves, with 'Hips' under it walking
  // forward at 1 m/s and turning left by a degree a frame, for 30 frames.
  const Motion file = loadTestFile("root_at_origin.bvh");
  MotionDatabase db = makeMotionDatabase(clips({"root_at_origin.bvh"}));
  const int hips = file.skeleton().find("Hips");
  REQUIRE(hips == 1);
  CHECK(db.roles.pelvis == hips);
  CHECK(db.rootMotion.joint == hips);
  CHECK(db.rootMotion.jointName == "Hips");
  CHECK(db.rootMotion.fileRootTravel == 0);
  CHECK_THAT(db.rootMotion.sentence, Catch::Contains("'Hips'") && Catch::Contains("file's root 'Root'"));

  // The avatar frame travels and turns with the hips: 29 frames at 1 m/s, 29 degrees.
  const Annotation& a = db.clips.front().annotation;
  const AvatarFrame& first = a.frames.front();
  const AvatarFrame& last = a.frames.back();
  CHECK((last.origin - first.origin).norm() == Approx(29.0 / 30.0).margin(0.01));
  CHECK(last.yaw - first.yaw == Approx(29.0 * std::numbers::pi / 180).margin(1e-3));
  // The file's first frame faces +Z (the rest pose's facing) and walks that way.
  CHECK(last.origin.z() - first.origin.z() == Approx(29.0 / 30.0).margin(0.01));

  // Every joint below the pelvis stands exactly where the file puts it, and joint 0 where
  // the hips are.
  const Motion& moved = db.clips.front().motion;
  const std::vector<Eigen::Vector3d> before = jointPositions(file), after = jointPositions(moved);
  const std::size_t joints = file.skeleton().jointCount();
  double worst = 0;
  for (std::size_t f = 0; f < file.frameCount(); ++f) {
    for (std::size_t j = 1; j < joints; ++j) worst = std::max(worst, (before[f * joints + j] - after[f * joints + j]).norm());
    worst = std::max(worst, (before[f * joints + 1] - after[f * joints]).norm());
  }
  CHECK(worst < 1e-9);

  // Setting the pelvis role to the file's root keeps the file's root motion: no travel.
  MotionDatabase kept = makeMotionDatabase(clips({"root_at_origin.bvh"}), RoleOverrides{{"pelvis", "Root"}});
  CHECK(kept.rootMotion.joint == 0);
  CHECK((kept.clips.front().annotation.frames.back().origin - kept.clips.front().annotation.frames.front().origin)
            .norm() < 1e-9);
}

TEST_CASE("moving the root motion twice changes nothing more (a cached graph's clips)", "[motion][root_motion]") {
  const Motion file = loadTestFile("root_at_origin.bvh");
  RootMotionReport once, twice;
  const Motion a = moveRootToPelvis(file, 1, "root_at_origin.bvh", once);
  const Motion b = moveRootToPelvis(a, 1, "root_at_origin.bvh", twice);
  CHECK(once.sentence == twice.sentence);
  for (std::size_t f = 0; f < file.frameCount(); ++f)
    for (std::size_t j = 0; j < file.skeleton().jointCount(); ++j) {
      CHECK(a.rotation(f, j).angularDistance(b.rotation(f, j)) < 1e-12);
      CHECK((a.localTranslation(f, j) - b.localTranslation(f, j)).norm() < 1e-12);
    }
}

TEST_CASE("a root joint without channels gains them when it takes the hips' motion", "[motion][root_motion]") {
  const Motion file = loadTestFile("root_at_origin.bvh");
  std::vector<Joint> joints(file.skeleton().joints().begin(), file.skeleton().joints().end());
  joints[0].channels.clear();
  joints[0].offset = {0, 0.5, 0};
  auto bare = std::make_shared<const Skeleton>(joints);
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  for (std::size_t f = 0; f < file.frameCount(); ++f) {
    for (std::size_t j = 0; j < joints.size(); ++j) rotations.push_back(file.rotation(f, j));
    for (const int j : bare->translatedJoints()) translations.push_back(file.localTranslation(f, static_cast<std::size_t>(j)));
  }
  const Motion noChannels(bare, file.frameTime(), rotations, translations);
  RootMotionReport report;
  const Motion moved = moveRootToPelvis(noChannels, 1, "bare", report);
  CHECK(moved.skeleton().translationSlot(0) == 0);
  CHECK(moved.skeleton().joint(0).channels.size() == 6);
  const std::vector<Eigen::Vector3d> before = jointPositions(noChannels), after = jointPositions(moved);
  for (std::size_t k = 0; k < before.size(); ++k)
    if (k % joints.size() != 0) CHECK((before[k] - after[k]).norm() < 1e-9);
}

TEST_CASE("a second branch above the pelvis is refused, naming the joint and the role that keeps the file's root",
          "[motion][root_motion]") {
  const Motion file = loadTestFile("root_at_origin.bvh");
  std::vector<Joint> joints(file.skeleton().joints().begin(), file.skeleton().joints().end());
  Joint prop;
  prop.name = "Prop";
  prop.parent = 0;
  prop.offset = {0.3, 0, 0};
  joints.push_back(prop);
  auto branched = std::make_shared<const Skeleton>(joints);
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  for (std::size_t f = 0; f < file.frameCount(); ++f) {
    for (std::size_t j = 0; j < file.skeleton().jointCount(); ++j) rotations.push_back(file.rotation(f, j));
    rotations.push_back(Eigen::Quaterniond::Identity());
    for (const Eigen::Vector3d& t : file.translations(f)) translations.push_back(t);
  }
  const Motion motion(branched, file.frameTime(), rotations, translations);
  RootMotionReport report;
  CHECK_THROWS_WITH(moveRootToPelvis(motion, 1, "prop.bvh", report),
                    Catch::Contains("prop.bvh: root motion") && Catch::Contains("found 'Root' with 2 children") &&
                        Catch::Contains("roles: {pelvis: Root}"));
}

TEST_CASE("one actor's takes load together though each bakes its start into the hips", "[motion][root_motion]") {
  // take_a.bvh and take_b.bvh: every file's hips offset is where its take starts (0 m and
  // 5 m from the origin), and 'Ab' is animated with position channels that hold its bone
  // (8 and 8.2 cm) whatever its OFFSET says (8 and 12 cm). Compared where bones are fixed,
  // they are one body.
  const MotionDatabase db = makeMotionDatabase(clips({"take_a.bvh", "take_b.bvh"}));
  CHECK(db.clips.size() == 2);
  CHECK(db.rootMotion.jointName == "Hips");
  // The second take starts 5 m away and walks 0.6 m/s: its avatar frame says so.
  const Annotation& b = db.clips[1].annotation;
  CHECK(std::hypot(b.frames.front().origin.x(), b.frames.front().origin.z()) == Approx(5.0).margin(0.01));

  // A truly different body is still refused with the bone that differs: a position channel
  // that holds a bone 1.5 times as long.
  std::vector<std::pair<std::string, Motion>> different = clips({"take_a.bvh"});
  const Motion b15 = loadTestFile("take_b.bvh").scaled(1.5);
  different.emplace_back("take_b_large.bvh", b15);
  CHECK_THROWS_WITH(makeMotionDatabase(std::move(different)),
                    Catch::Contains("take_a.bvh and take_b_large.bvh have different skeletons") &&
                        Catch::Contains("bone 'Ab' is 0.080 m in the first, 0.123 m in the second"));
}

TEST_CASE("a head without a head top measures the person in proportion, and CMU's head top agrees",
          "[motion][roles][data]") {
  // CMU subject 13 stands about 1.63 m (DATA.md) with his head end site. Without it, the
  // stand-in (kHeadTopPerSpine of the pelvis-to-head distance) gives him the same height
  // within 1 cm. boxer21.bvh (a zero-length head end site) is in annotation_test.cpp.
  const Motion cmu = test::loadMocap("cmu/bvh/13_17_boxing.bvh").motion;
  const SkeletonRoles withTop = findRoles(cmu.skeleton());
  std::vector<Joint> joints(cmu.skeleton().joints().begin(), cmu.skeleton().joints().end());
  joints[static_cast<std::size_t>(withTop.head)].endSite = Eigen::Vector3d::Zero();
  const Skeleton headless(joints);
  const SkeletonRoles stand = findRoles(headless);
  CHECK(stand.restHeight == Approx(withTop.restHeight).margin(0.01));
  CHECK(withTop.restHeight == Approx(1.63).margin(0.02));
  CHECK(stand.headTopOffset.norm() > joints[static_cast<std::size_t>(withTop.head)].offset.norm());
}

}  // namespace root_motion_test
