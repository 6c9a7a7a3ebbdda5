#include <map>

#include <catch2/catch.hpp>

#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace asf_amc_test {

using namespace mgrl;

namespace {

// CMU's BVH release names for the ASF bones (DATA.md): a BVH joint sits where its bone
// starts, as mgrl's ASF conversion places it.
const std::map<std::string, std::string> kBvhToAsf = {
    {"Hips", "root"},           {"LHipJoint", "lhipjoint"},     {"LeftUpLeg", "lfemur"},
    {"LeftLeg", "ltibia"},      {"LeftFoot", "lfoot"},          {"LeftToeBase", "ltoes"},
    {"RHipJoint", "rhipjoint"}, {"RightUpLeg", "rfemur"},       {"RightLeg", "rtibia"},
    {"RightFoot", "rfoot"},     {"RightToeBase", "rtoes"},      {"LowerBack", "lowerback"},
    {"Spine", "upperback"},     {"Spine1", "thorax"},           {"Neck", "lowerneck"},
    {"Neck1", "upperneck"},     {"Head", "head"},               {"LeftShoulder", "lclavicle"},
    {"LeftArm", "lhumerus"},    {"LeftForeArm", "lradius"},     {"LeftHand", "lwrist"},
    {"LeftFingerBase", "lhand"}, {"LeftHandIndex1", "lfingers"}, {"LThumb", "lthumb"},
    {"RightShoulder", "rclavicle"}, {"RightArm", "rhumerus"},   {"RightForeArm", "rradius"},
    {"RightHand", "rwrist"},    {"RightFingerBase", "rhand"},   {"RightHandIndex1", "rfingers"},
    {"RThumb", "rthumb"}};

}  // namespace

TEST_CASE("BVH and ASF/AMC of CMU 13_17 give the same joint positions within 1 mm", "[asf][data]") {
  const LoadedMotion bvh = test::loadMocap("cmu/bvh/13_17_boxing.bvh");
  const LoadedMotion amc = test::loadMocap("cmu/asfamc/13_17.amc");
  CHECK(bvh.units == LengthUnit::Cmu);
  CHECK(amc.units == LengthUnit::Cmu);
  REQUIRE(bvh.motion.frameCount() == 4840);
  REQUIRE(amc.motion.frameCount() == bvh.motion.frameCount());
  REQUIRE(bvh.motion.fps() == Approx(120.0).epsilon(1e-5));
  REQUIRE(amc.motion.fps() == Approx(120.0));

  const Skeleton& a = bvh.motion.skeleton();
  const Skeleton& b = amc.motion.skeleton();
  REQUIRE(a.jointCount() == kBvhToAsf.size());
  REQUIRE(b.jointCount() == kBvhToAsf.size());
  std::vector<int> match(a.jointCount());
  for (std::size_t j = 0; j < a.jointCount(); ++j) {
    match[j] = b.find(kBvhToAsf.at(a.joint(j).name));
    REQUIRE(match[j] >= 0);
  }
  const auto pa = jointPositions(bvh.motion);
  const auto pb = jointPositions(amc.motion);
  double worst = 0;
  for (std::size_t f = 0; f < bvh.motion.frameCount(); ++f)
    for (std::size_t j = 0; j < a.jointCount(); ++j)
      worst = std::max(worst, (pa[f * a.jointCount() + j] - pb[f * b.jointCount() + static_cast<std::size_t>(match[j])]).norm());
  INFO("largest BVH/AMC joint distance " << worst * 1000 << " mm");
  CHECK(worst < 0.001);
}

TEST_CASE("an AMC file finds its subject's ASF beside it", "[asf]") {
  CHECK(defaultAsfFor("/data/cmu/13_17.amc") == std::filesystem::path("/data/cmu/13.asf"));
  CHECK(defaultAsfFor("135_06.amc") == std::filesystem::path("135.asf"));
}

TEST_CASE("ASF bones become joints ordered parent before child with end sites on leaves", "[asf][data]") {
  const AsfSkeleton asf = parseAsf(readFile(test::mocap() / "cmu/asfamc/13.asf"), "13.asf");
  const Skeleton& s = *asf.skeleton;
  REQUIRE(s.jointCount() == 31);
  CHECK(s.joint(0).name == "root");
  for (std::size_t j = 1; j < s.jointCount(); ++j) CHECK(s.joint(j).parent < static_cast<int>(j));
  CHECK(s.joint(static_cast<std::size_t>(s.find("ltoes"))).endSite.has_value());
  CHECK_FALSE(s.joint(static_cast<std::size_t>(s.find("lfemur"))).endSite.has_value());
  CHECK(asf.lengthPerInch == Approx(0.45));
}

}  // namespace asf_amc_test
