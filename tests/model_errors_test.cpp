// Errors from building the in-memory model directly (not through a loader) and from file
// I/O: each names what was expected and what was found.

#include <fstream>

#include <catch2/catch.hpp>

#include "mgrl/motion/annotation.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/motion/roles.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace model_errors_test {

using namespace mgrl;
using Catch::Contains;

namespace {

Joint joint(const std::string& name, int parent, Eigen::Vector3d offset = Eigen::Vector3d::Zero()) {
  Joint j;
  j.name = name;
  j.parent = parent;
  j.offset = offset;
  return j;
}

std::shared_ptr<const Skeleton> chain() {
  return std::make_shared<const Skeleton>(std::vector<Joint>{joint("a", -1), joint("b", 0, {0, 1, 0})});
}

}  // namespace

TEST_CASE("a skeleton rejects empty, duplicate and misordered joints", "[model][errors]") {
  CHECK_THROWS_WITH(Skeleton(std::vector<Joint>{}), Contains("expected at least one joint, found none"));
  CHECK_THROWS_WITH(Skeleton({joint("a", -1), joint("", 0)}), Contains("joint 1: expected a name, found an empty one"));
  CHECK_THROWS_WITH(Skeleton({joint("a", -1), joint("a", 0)}), Contains("expected unique joint names, found 'a' twice"));
  CHECK_THROWS_WITH(Skeleton({joint("a", -1), joint("b", 1)}), Contains("joint 'b' (index 1): expected a parent index in [0, 1), found 1"));
  CHECK_THROWS_WITH(Skeleton({joint("a", 0)}), Contains("expected a parent index of -1 (the root), found 0"));
}

TEST_CASE("a motion rejects mismatched arrays, bad frame times and bad slices", "[model][errors]") {
  const auto skeleton = chain();
  const std::vector<Eigen::Quaterniond> two(2, Eigen::Quaterniond::Identity());
  CHECK_THROWS_WITH(Motion(nullptr, 0.1, two, {}), Contains("expected a skeleton, found none"));
  CHECK_THROWS_WITH(Motion(skeleton, 0, two, {}), Contains("expected a positive frame time, found 0"));
  CHECK_THROWS_WITH(Motion(skeleton, 0.1, {}, {}), Contains("expected 2 rotations and 0 translations per frame, found 0 and 0"));
  CHECK_THROWS_WITH(Motion(skeleton, 0.1, std::vector<Eigen::Quaterniond>(3, Eigen::Quaterniond::Identity()), {}),
                    Contains("found 3 and 0"));
  const Motion m(skeleton, 0.1, two, {});
  CHECK(m.slice(0, 1).frameCount() == 1);
  CHECK_THROWS_WITH(m.slice(0, 2), Contains("expected a frame range inside [0, 1), found [0, 2)"));
  CHECK_THROWS_WITH(m.slice(1, 0), Contains("found [1, 1)"));
}

TEST_CASE("reading a directory or a missing file says why", "[model][errors]") {
  CHECK_THROWS_WITH(readFile(test::testData()), Contains("expected a file, found a directory"));
  CHECK_THROWS_WITH(readFile(test::testData() / "no_such_file.bvh"), Contains("cannot open: No such file"));
}

TEST_CASE("a failed atomic write leaves no file behind", "[model][errors]") {
  const auto folder = std::filesystem::temp_directory_path() / "mgrl_atomic_write_test";
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  // A regular file where a folder should be: the write cannot happen, even as root.
  std::ofstream(folder / "blocker") << "x";
  CHECK_THROWS_WITH(writeFileAtomically(folder / "blocker" / "out.bvh", "data"), Contains("out.bvh: cannot write"));
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(folder)) ++entries;
  CHECK(entries == 1);

  writeFileAtomically(folder / "out.bvh", "data");
  CHECK(readFile(folder / "out.bvh") == "data");
  entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(folder)) ++entries;
  CHECK(entries == 2);  // blocker and out.bvh, no temporary left over
  std::filesystem::remove_all(folder);
}

TEST_CASE("roles reject a rest pose without a usable body axis", "[roles][errors]") {
  auto names = test::humanoidNames();
  const Skeleton normal = test::humanoid(names);
  std::vector<Joint> joints(normal.joints().begin(), normal.joints().end());

  // Head at the pelvis: no up axis.
  auto collapsed = joints;
  collapsed[1].offset.setZero();  // spine
  collapsed[2].offset.setZero();  // head
  CHECK_THROWS_WITH(findRoles(Skeleton(collapsed), {}, "flat.bvh"),
                    Contains("flat.bvh: expected head and pelvis apart in the rest pose, found them at the same point"));

  // Both hips on the same spot: no left-right axis.
  auto narrow = joints;
  for (Joint& j : narrow)
    if (j.name == "LeftUpLeg" || j.name == "RightUpLeg") j.offset.setZero();
  CHECK_THROWS_WITH(findRoles(Skeleton(narrow), {}, "narrow.bvh"),
                    Contains("narrow.bvh: expected left and right hips apart in the rest pose, found them level"));
}

TEST_CASE("annotation rejects a glitch threshold below the punch threshold", "[annotation][errors]") {
  AnnotationParams p;
  p.punchMaxSpeed_mps = 1.0;
  CHECK_THROWS_WITH(p.validate(), Contains("punch_max_speed_mps: expected a value above punch_min_speed_mps (2), found 1"));
}

}  // namespace model_errors_test
