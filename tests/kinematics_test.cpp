#include <algorithm>

#include <catch2/catch.hpp>

#include "mgrl/motion/kinematics.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace kinematics_test {

using namespace mgrl;

namespace {

// The textbook recursive walk, to cross-check the linear pass (Pinocchio style).
void recursiveFk(const Motion& m, std::size_t f, int joint, const Eigen::Quaterniond& parentRotation,
                 const Eigen::Vector3d& parentPosition, std::vector<Eigen::Vector3d>& out) {
  const Eigen::Vector3d position = m.skeleton().joint(static_cast<std::size_t>(joint)).parent < 0
                                       ? m.localTranslation(f, 0)
                                       : Eigen::Vector3d(parentPosition + parentRotation * m.localTranslation(f, static_cast<std::size_t>(joint)));
  const Eigen::Quaterniond rotation = parentRotation * m.rotation(f, static_cast<std::size_t>(joint));
  out[static_cast<std::size_t>(joint)] = position;
  for (std::size_t c = 0; c < m.skeleton().jointCount(); ++c)
    if (m.skeleton().joint(c).parent == joint) recursiveFk(m, f, static_cast<int>(c), rotation, position, out);
}

}  // namespace

TEST_CASE("the linear FK pass agrees with a recursive walk", "[kinematics][data]") {
  for (const char* file : {"cmu/bvh/13_17_boxing.bvh", "snu_martial_arts/motion/s_001_3_1.bvh", "cmu/asfamc/13_18.amc"}) {
    CAPTURE(file);
    const Motion m = test::loadMocap(file).motion;
    const std::size_t n = m.skeleton().jointCount();
    const auto linear = jointPositions(m);
    std::vector<Eigen::Vector3d> recursive(n);
    for (std::size_t f = 0; f < m.frameCount(); f += 37) {
      recursiveFk(m, f, 0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), recursive);
      for (std::size_t j = 0; j < n; ++j) CHECK((linear[f * n + j] - recursive[j]).norm() < 1e-12);
    }
  }
}

TEST_CASE("bone lengths stay constant over every frame of real capture", "[kinematics][data]") {
  const Motion m = test::loadMocap("cmu/bvh/13_17_boxing.bvh").motion;
  const std::size_t n = m.skeleton().jointCount();
  const auto p = jointPositions(m);
  double worst = 0;
  for (std::size_t f = 0; f < m.frameCount(); ++f)
    for (std::size_t j = 1; j < n; ++j) {
      const double length = (p[f * n + j] - p[f * n + static_cast<std::size_t>(m.skeleton().joint(j).parent)]).norm();
      worst = std::max(worst, std::abs(length - m.skeleton().joint(j).offset.norm()));
    }
  CHECK(worst < 1e-9);
}

TEST_CASE("velocities are central differences, one-sided at the ends", "[kinematics]") {
  // One point moving as x = t^2 sampled at 10 Hz: central differences are exact for a
  // parabola, one-sided ones are off by dt.
  std::vector<Eigen::Vector3d> positions;
  for (int f = 0; f < 5; ++f) positions.emplace_back(0.01 * f * f, 0, 0);
  const auto v = velocities(positions, 1, 0.1);
  CHECK(v[2].x() == Approx(2 * 0.2));
  CHECK(v[0].x() == Approx(0.1));  // (0.01 - 0) / 0.1
  CHECK(v[4].x() == Approx((0.16 - 0.09) / 0.1));
  CHECK(velocities(std::vector<Eigen::Vector3d>(1, Eigen::Vector3d::Ones()), 1, 0.1)[0].norm() == 0);
}

TEST_CASE("redoing one subtree's kinematics gives what the full pass gives", "[kinematics][data]") {
  const Motion m = test::loadMocap("cmu/bvh/13_17_boxing.bvh").motion;
  const Skeleton& skeleton = m.skeleton();
  const std::size_t n = skeleton.jointCount();
  const int hip = skeleton.find("LeftUpLeg");
  REQUIRE(hip > 0);
  const std::vector<int> leg = subtreeJoints(skeleton, hip);
  // Exactly the hip and the joints whose parent chain reaches it.
  for (std::size_t j = 0; j < n; ++j) {
    bool below = false;
    for (int k = static_cast<int>(j); k >= 0; k = skeleton.joint(static_cast<std::size_t>(k)).parent)
      below = below || k == hip;
    CHECK((std::find(leg.begin(), leg.end(), static_cast<int>(j)) != leg.end()) == below);
  }
  CHECK(std::is_sorted(leg.begin(), leg.end()));
  CHECK(leg.size() >= 3);
  CHECK(subtreeJoints(skeleton, -1).empty());
  CHECK(subtreeJoints(skeleton, static_cast<int>(n)).empty());

  std::vector<Eigen::Quaterniond> local(n), rotations(n), fullRotations(n);
  std::vector<Eigen::Vector3d> translations(n), positions(n), fullPositions(n);
  for (std::size_t j = 0; j < n; ++j) {
    local[j] = m.rotation(40, j);
    translations[j] = m.localTranslation(40, j);
  }
  forwardKinematics(skeleton, local, translations, rotations, positions);
  // Turn the hip and the knee, then redo the leg alone.
  local[static_cast<std::size_t>(hip)] =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX())) * local[static_cast<std::size_t>(hip)];
  local[static_cast<std::size_t>(leg[1])] =
      Eigen::Quaterniond(Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitZ())) * local[static_cast<std::size_t>(leg[1])];
  const std::vector<Eigen::Vector3d> before = positions;
  forwardKinematicsOf(skeleton, leg, local, translations, rotations, positions);
  forwardKinematics(skeleton, local, translations, fullRotations, fullPositions);
  for (std::size_t j = 0; j < n; ++j) {
    CAPTURE(j);
    CHECK(positions[j] == fullPositions[j]);
    CHECK(rotations[j].coeffs() == fullRotations[j].coeffs());
  }
  CHECK((positions[static_cast<std::size_t>(leg.back())] - before[static_cast<std::size_t>(leg.back())]).norm() > 0.05);
}

}  // namespace kinematics_test
