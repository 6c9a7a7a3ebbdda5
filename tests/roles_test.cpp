#include <catch2/catch.hpp>

#include "mgrl/error.hpp"
#include "mgrl/roles.hpp"
#include "test_support.hpp"

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
  // SNU's rest pose lies along +X with one leg up: height must still be a person's.
  CHECK(s.restHeight == Approx(1.68).margin(0.1));
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
