#include <catch2/catch.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/roles.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace roles_test {

using namespace mgrl;

namespace {

std::string nameOf(const Skeleton& s, int j) { return s.joint(static_cast<std::size_t>(j)).name; }

}  // namespace

TEST_CASE("roles are found by name in CMU BVH, CMU ASF and SNU skeletons", "[roles][data]") {
  const LoadedMotion bvhMotion = test::loadMocap("cmu/bvh/13_17_boxing.bvh");
  const Skeleton& bvh = bvhMotion.motion.skeleton();
  const SkeletonRoles r = findRoles(bvh);
  CHECK(nameOf(bvh, r.fist[0]) == "LeftFingerBase");
  CHECK(nameOf(bvh, r.wrist[1]) == "RightHand");
  CHECK(nameOf(bvh, r.forearm[0]) == "LeftForeArm");
  CHECK(nameOf(bvh, r.shoulder[1]) == "RightArm");
  CHECK(nameOf(bvh, r.ankle[0]) == "LeftFoot");
  CHECK(nameOf(bvh, r.toe[1]) == "RightToeBase");
  CHECK(nameOf(bvh, r.head) == "Head");
  CHECK(nameOf(bvh, r.pelvis) == "Hips");
  // The knuckles: the End Site of LeftHandIndex1 (DATA.md).
  CHECK(nameOf(bvh, r.fistTipJoint[0]) == "LeftHandIndex1");
  CHECK(r.fistTipOffset[0].norm() > 0);
  CHECK(r.restHeight == Approx(1.63).margin(0.02));  // DATA.md: subject 13 is about 1.63 m
  CHECK(r.forward.z() > 0.99);  // CMU's rest pose faces +Z

  const LoadedMotion asfMotion = test::loadMocap("cmu/asfamc/13_17.amc");
  const Skeleton& asf = asfMotion.motion.skeleton();
  const SkeletonRoles a = findRoles(asf);
  CHECK(nameOf(asf, a.fist[0]) == "lhand");
  CHECK(nameOf(asf, a.wrist[0]) == "lwrist");
  CHECK(nameOf(asf, a.forearm[1]) == "rradius");
  CHECK(nameOf(asf, a.shoulder[0]) == "lhumerus");
  CHECK(nameOf(asf, a.toe[0]) == "ltoes");
  CHECK(nameOf(asf, a.pelvis) == "root");

  const LoadedMotion snuMotion = test::loadMocap("snu_martial_arts/motion/s_001_3_1.bvh");
  const Skeleton& snu = snuMotion.motion.skeleton();
  const SkeletonRoles s = findRoles(snu);
  CHECK(nameOf(snu, s.fist[0]) == "LeftHand");
  CHECK(nameOf(snu, s.toe[1]) == "RightToe");
  // SNU's rest pose lies along +X with one leg up: height must still be a person's. Its
  // head end site has zero length: the head top continues the neck, kHeadTopPerSpine of
  // the 69 cm from pelvis to head (12.8 cm; the neck bone alone is 9.3 cm).
  CHECK(s.restHeight == Approx(1.78).margin(0.05));
  CHECK(s.headTopOffset.norm() == Approx(0.128).margin(0.002));
}

TEST_CASE("roles are found for Mixamo-like and _L/_R namings", "[roles]") {
  const Skeleton mixamo = test::humanoid({"mixamorig:Hips", "mixamorig:Spine", "mixamorig:Head", "mixamorig:LeftArm",
                                    "mixamorig:LeftForeArm", "mixamorig:LeftHand", "mixamorig:LeftUpLeg",
                                    "mixamorig:LeftLeg", "mixamorig:LeftFoot", "mixamorig:LeftToeBase",
                                    "mixamorig:RightArm", "mixamorig:RightForeArm", "mixamorig:RightHand",
                                    "mixamorig:RightUpLeg", "mixamorig:RightLeg", "mixamorig:RightFoot",
                                    "mixamorig:RightToeBase"});
  const SkeletonRoles m = findRoles(mixamo);
  CHECK(nameOf(mixamo, m.fist[1]) == "mixamorig:RightHand");
  CHECK(nameOf(mixamo, m.shoulder[0]) == "mixamorig:LeftArm");
  // Head top (spine 0.3 + head 0.3 + end 0.2 above the pelvis) down to the toe tip
  // (0.9 + 0.07 below it).
  CHECK(m.restHeight == Approx(0.8 + 0.97).margin(1e-9));

  const Skeleton suffixed = test::humanoid({"pelvis", "spine_01", "head", "upperarm_l", "lowerarm_l", "hand_l", "thigh_l",
                                      "calf_l", "foot_l", "ball_l", "upperarm_r", "lowerarm_r", "hand_r", "thigh_r",
                                      "calf_r", "foot_r", "ball_r"});
  const SkeletonRoles u = findRoles(suffixed);
  CHECK(nameOf(suffixed, u.forearm[0]) == "lowerarm_l");
  CHECK(nameOf(suffixed, u.toe[1]) == "ball_r");
  CHECK(nameOf(suffixed, u.pelvis) == "pelvis");
  CHECK(u.forward.z() == Approx(1.0));
}

TEST_CASE("a role can be overridden, and a missing role lists the skeleton's joints", "[roles]") {
  const Skeleton odd = test::humanoid({"Hips", "Spine", "Skull", "LeftArm", "LeftForeArm", "LeftHand", "LeftUpLeg", "LeftLeg",
                                 "LeftFoot", "LeftToe", "RightArm", "RightForeArm", "RightHand", "RightUpLeg",
                                 "RightLeg", "RightFoot", "RightToe"});
  CHECK_THROWS_WITH(findRoles(odd, {}, "odd.bvh"),
                    Catch::Contains("odd.bvh: expected a joint for role head") && Catch::Contains("Skull") &&
                        Catch::Contains("--role head=JOINT"));
  const SkeletonRoles r = findRoles(odd, {{"head", "Skull"}}, "odd.bvh");
  CHECK(nameOf(odd, r.head) == "Skull");
  CHECK_THROWS_WITH(findRoles(odd, {{"head", "Nope"}}, "odd.bvh"),
                    Catch::Contains("role head: expected a joint of the skeleton, found 'Nope'"));
  CHECK_THROWS_WITH(findRoles(odd, {{"left_tail", "Skull"}}, "odd.bvh"),
                    Catch::Contains("expected a role name") && Catch::Contains("left_fist"));
}

TEST_CASE("a skeleton without finger joints uses the wrist's end site as the fist, and says so once",
          "[roles]") {
  // tests/data/boxer21.bvh: Hips/Ab/Chest/Neck/Head, LeftCollar/LeftShoulder/LeftElbow/
  // LeftWrist with an 8 cm end site, legs Hip/Knee/Ankle/Toe; no finger joints.
  const LoadedMotion loaded = loadMotion(test::testData() / "boxer21.bvh");
  const Skeleton& skeleton = loaded.motion.skeleton();
  std::vector<std::string> warnings;
  const SkeletonRoles r = findRoles(skeleton, {}, "boxer21.bvh", [&](const std::string& w) { warnings.push_back(w); });
  for (int s = 0; s < 2; ++s) {
    CAPTURE(s);
    CHECK(r.fist[s] == r.wrist[s]);
    CHECK(r.fistTipJoint[s] == r.wrist[s]);
    CHECK(r.fistTipOffset[s].norm() == Approx(0.08));
  }
  CHECK(nameOf(skeleton, r.wrist[0]) == "LeftWrist");
  CHECK(nameOf(skeleton, r.forearm[1]) == "RightElbow");
  CHECK(nameOf(skeleton, r.ankle[0]) == "LeftAnkle");
  REQUIRE(warnings.size() == 1);
  CHECK_THAT(warnings[0], Catch::Contains("boxer21.bvh: no fist joint") &&
                              Catch::Contains("using LeftWrist's end site for left_fist and RightWrist's end site for "
                                              "right_fist"));

  // A skeleton with fist joints says nothing, and a wrist without an end site is its own tip.
  warnings.clear();
  const Skeleton plain = test::humanoid(test::humanoidNames());
  (void)findRoles(plain, {}, "plain", [&](const std::string& w) { warnings.push_back(w); });
  CHECK(warnings.empty());
  std::vector<Joint> joints(skeleton.joints().begin(), skeleton.joints().end());
  for (Joint& j : joints)
    if (j.name == "LeftWrist") j.endSite.reset();
  const SkeletonRoles bare = findRoles(Skeleton(joints), {}, "bare.bvh", [&](const std::string& w) { warnings.push_back(w); });
  CHECK(bare.fistTipJoint[0] == bare.wrist[0]);
  CHECK(bare.fistTipOffset[0].norm() == 0);
  REQUIRE(warnings.size() == 1);
  CHECK_THAT(warnings[0], Catch::Contains("using LeftWrist for left_fist and RightWrist's end site for right_fist"));
}

TEST_CASE("a zero-length head end site is continued along the neck by a head in proportion", "[roles]") {
  // boxer21.bvh: Head 10 cm above Neck, 60 cm above the hips, with a zero-length end site;
  // toes point down in the rest pose (toe tip 16 cm below the ankle). Head top:
  // kHeadTopPerSpine * 60 cm = 11.16 cm above the head joint, 71.16 cm above the hips; toe
  // tip 104 cm below.
  const LoadedMotion loaded = loadMotion(test::testData() / "boxer21.bvh");
  const SkeletonRoles r = findRoles(loaded.motion.skeleton());
  CHECK(r.headTopOffset.y() == Approx(kHeadTopPerSpine * 0.60));
  CHECK(r.restHeight == Approx(1.7516));
  // A short neck bone does not shorten the person: half the neck, the same head top.
  std::vector<Joint> joints(loaded.motion.skeleton().joints().begin(), loaded.motion.skeleton().joints().end());
  const int head = loaded.motion.skeleton().find("Head");
  joints[static_cast<std::size_t>(head)].offset.y() = 0.05;
  joints[static_cast<std::size_t>(head) - 1].offset.y() += 0.05;
  const SkeletonRoles shortNeck = findRoles(Skeleton(joints));
  CHECK(shortNeck.restHeight == Approx(1.7516));
}

}  // namespace roles_test
