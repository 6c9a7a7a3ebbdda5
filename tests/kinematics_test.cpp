#include <catch2/catch.hpp>

#include "mgrl/motion/kinematics.hpp"
#include "test_support.hpp"

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
