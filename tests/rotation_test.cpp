#include <array>
#include <numbers>
#include <random>

#include <catch2/catch.hpp>

#include "mgrl/core/rotation.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace rotation_test {

using namespace mgrl;

namespace {

const std::array<std::array<Axis, 3>, 6> kOrders = {{{Axis::X, Axis::Y, Axis::Z}, {Axis::X, Axis::Z, Axis::Y},
                                                     {Axis::Y, Axis::X, Axis::Z}, {Axis::Y, Axis::Z, Axis::X},
                                                     {Axis::Z, Axis::X, Axis::Y}, {Axis::Z, Axis::Y, Axis::X}}};

double angleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b); }

}  // namespace

TEST_CASE("composeEuler applies the listed axes left to right", "[rotation]") {
  // BVH "Zrotation Xrotation" means R = Rz * Rx: a vector is rotated about X first.
  const std::array<Axis, 2> axes{Axis::Z, Axis::X};
  const std::array<double, 2> angles{std::numbers::pi / 2, std::numbers::pi / 2};
  const Eigen::Vector3d v = composeEuler(axes, angles) * Eigen::Vector3d::UnitY();
  // Rx(90) takes +Y to +Z; Rz(90) leaves +Z alone.
  CHECK((v - Eigen::Vector3d::UnitZ()).norm() < 1e-12);
}

TEST_CASE("decomposeEuler inverts composeEuler for every Tait-Bryan order", "[rotation]") {
  const unsigned seed = 12345;
  CAPTURE(seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  for (const auto& order : kOrders) {
    for (int i = 0; i < 2000; ++i) {
      const std::array<double, 3> a{angle(rng), angle(rng) / 2, angle(rng)};
      const Eigen::Quaterniond q = composeEuler(order, a);
      const auto back = decomposeEuler(q, order);
      CHECK(angleBetween(composeEuler(order, back), q) < 1e-9);
    }
  }
}

TEST_CASE("decomposeEuler survives gimbal lock", "[rotation]") {
  for (const auto& order : kOrders) {
    for (double outer : {-2.0, -0.3, 0.0, 1.1, 3.0}) {
      for (double middle : {std::numbers::pi / 2, -std::numbers::pi / 2}) {
        const std::array<double, 3> a{outer, middle, 0.7};
        const Eigen::Quaterniond q = composeEuler(order, a);
        const auto back = decomposeEuler(q, order, {0, 0, 0.7});
        CAPTURE(outer, middle);
        CHECK(angleBetween(composeEuler(order, back), q) < 1e-7);
      }
    }
  }
}

TEST_CASE("decomposeEuler stays continuous with the previous frame", "[rotation]") {
  // A joint spinning past 180 degrees must not jump by 360 in the exported curve.
  const std::array<Axis, 3> order{Axis::Z, Axis::Y, Axis::X};
  std::array<double, 3> previous{0, 0, 0};
  for (int step = 0; step <= 400; ++step) {
    const double a = step * 0.02;  // up to 8 rad, beyond +pi
    const auto angles = decomposeEuler(composeEuler(order, std::array<double, 3>{a, 0.2, -0.1}), order, previous);
    for (int k = 0; k < 3; ++k) CHECK(std::abs(angles[k] - previous[k]) < 0.1 + (step == 0 ? 1.0 : 0.0));
    previous = angles;
  }
  CHECK(previous[0] == Approx(8.0).margin(1e-9));
}

}  // namespace rotation_test
