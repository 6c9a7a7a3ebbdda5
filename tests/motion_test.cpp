#include <numbers>

#include <catch2/catch.hpp>

#include "mgrl/motion/kinematics.hpp"
#include "mgrl/core/error.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace motion_test {

using namespace mgrl;

namespace {

// A two-joint chain whose child spins about Y at `rate` rad/s, sampled at `fps`.
Motion spinningChain(double fps, std::size_t frames, double rate) {
  std::vector<Joint> joints(2);
  joints[0].name = "root";
  joints[0].channels = {{Channel::Kind::Position, Axis::X}, {Channel::Kind::Position, Axis::Y}, {Channel::Kind::Position, Axis::Z}};
  joints[1].name = "arm";
  joints[1].parent = 0;
  joints[1].offset = {0, 1, 0};
  joints[1].endSite = Eigen::Vector3d(1, 0, 0);
  auto skeleton = std::make_shared<const Skeleton>(joints);
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  for (std::size_t f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / fps;
    rotations.push_back(Eigen::Quaterniond::Identity());
    rotations.push_back(axisRotation(Axis::Y, rate * t));
    translations.emplace_back(2 * t, 0, 0);
  }
  return Motion(skeleton, 1.0 / fps, rotations, translations);
}

}  // namespace

TEST_CASE("resampling slerps rotations and lerps the root at non-integer ratios", "[motion]") {
  const Motion source = spinningChain(120, 121, 1.5);  // 1.0083 s, 1.5 rad/s
  const Motion out = resample(source, 50);
  CHECK(out.fps() == Approx(50));
  CHECK(std::abs(out.duration() - source.duration()) <= out.frameTime());
  for (std::size_t k = 0; k < out.frameCount(); ++k) {
    const double t = static_cast<double>(k) / 50;
    CAPTURE(k);
    CHECK(out.rotation(k, 1).angularDistance(axisRotation(Axis::Y, 1.5 * t)) < 1e-9);
    CHECK(out.localTranslation(k, 0).x() == Approx(2 * t).margin(1e-12));
  }
}

TEST_CASE("resampling rejects absurd frame rates", "[motion]") {
  const Motion m = spinningChain(30, 10, 1);
  CHECK_THROWS_AS(resample(m, 0), Error);
  CHECK_THROWS_AS(resample(m, -5), Error);
  CHECK_THROWS_AS(resample(m, 1e9), Error);
}

// A long capture at a high rate is refused, with its size, before anything is
// allocated (1001 s at 10000 fps would be 10.01 M frames).
TEST_CASE("resampling refuses a result too large for memory before allocating it", "[motion][errors]") {
  const Motion m = spinningChain(1, 1001, 1);
  REQUIRE(m.duration() == Approx(1001));
  REQUIRE_THROWS_WITH(resample(m, 10000), Catch::StartsWith("resample: 1001.0 s of motion at 10000 fps is 10010000 "
                                                            "frames") &&
                                              Catch::Contains("expected at most 10000000 frames"));
  CHECK(resample(m, 100).frameCount() > 100000);  // a big but sane request still works
}

TEST_CASE("resampling 120 to 30 fps keeps the duration and the joint paths", "[motion][data]") {
  const Motion source = test::loadMocap("cmu/bvh/13_17_boxing.bvh").motion;
  const Motion out = resample(source, 30);
  CHECK(out.frameCount() == 1210);
  CHECK(std::abs(out.duration() - source.duration()) <= out.frameTime());
  const std::size_t n = source.skeleton().jointCount();
  const auto ps = jointPositions(source), po = jointPositions(out);
  // Shared instants: every 4th source frame is an output frame, exactly.
  double worst = 0;
  for (std::size_t k = 0; k < out.frameCount(); ++k)
    for (std::size_t j = 0; j < n; ++j) worst = std::max(worst, (po[k * n + j] - ps[4 * k * n + j]).norm());
  CHECK(worst < 1e-9);

  // Between shared instants (120 -> 50 fps), samples follow the source path closely.
  const Motion fifty = resample(source, 50);
  const auto pf = jointPositions(fifty);
  worst = 0;
  for (std::size_t k = 0; k < fifty.frameCount(); ++k) {
    const double s = static_cast<double>(k) * 120.0 / 50.0;
    const auto i = static_cast<std::size_t>(s);
    const double u = s - static_cast<double>(i);
    if (i + 1 >= source.frameCount()) break;
    for (std::size_t j = 0; j < n; ++j)
      worst = std::max(worst, (pf[k * n + j] - ((1 - u) * ps[i * n + j] + u * ps[(i + 1) * n + j])).norm());
  }
  INFO("largest distance from the interpolated source path: " << worst * 1000 << " mm");
  CHECK(worst < 0.005);
}

TEST_CASE("loading with --fps resamples and reports the file's own rate", "[motion][data]") {
  LoadOptions options;
  options.fps = 30;
  const LoadedMotion loaded = test::loadMocap("cmu/bvh/13_18_boxing.bvh", options);
  CHECK(loaded.fileFps == Approx(120).epsilon(1e-4));
  CHECK(loaded.motion.fps() == Approx(30));
  CHECK(loaded.motion.duration() == Approx(25.0).margin(1.0 / 30));
}

}  // namespace motion_test
