#include <sstream>

#include <catch2/catch.hpp>

#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/core/text_scanner.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace bvh_roundtrip_test {

using namespace mgrl;

namespace {

// Channel values of a BVH text, frame after frame (everything after "Frame Time:").
std::vector<double> channelValues(const std::string& text) {
  const auto at = text.find("Frame Time:");
  REQUIRE(at != std::string::npos);
  std::istringstream in(text.substr(text.find('\n', at) + 1));
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    double v = 0;
    REQUIRE(parseDouble(token, v));
    values.push_back(v);
  }
  return values;
}

double largestJointDistance(const Motion& a, const Motion& b) {
  REQUIRE(a.frameCount() == b.frameCount());
  const auto pa = jointPositions(a), pb = jointPositions(b);
  double worst = 0;
  for (std::size_t i = 0; i < pa.size(); ++i) worst = std::max(worst, (pa[i] - pb[i]).norm());
  return worst;
}

}  // namespace

TEST_CASE("writing then reading a real BVH reproduces its channels and joint positions", "[bvh][data]") {
  for (const char* file : {"cmu/bvh/13_17_boxing.bvh", "snu_martial_arts/motion/s_019_2_1.bvh"}) {
    CAPTURE(file);
    const std::string original = readFile(test::mocap() / file);
    const LoadedMotion loaded = test::loadMocap(file);
    // Written in the file's own units, the channels are directly comparable.
    std::ostringstream out;
    writeBvh(out, loaded.motion, {1.0 / metresPer(loaded.units)});
    const std::string written = out.str();

    const auto before = channelValues(original);
    const auto after = channelValues(written);
    REQUIRE(before.size() == after.size());
    double worst = 0;
    for (std::size_t i = 0; i < before.size(); ++i) worst = std::max(worst, std::abs(before[i] - after[i]));
    INFO("largest channel difference " << worst);
    CHECK(worst < 1e-6);

    const Motion reread = parseBvh(written, "written.bvh").scaled(metresPer(loaded.units));
    CHECK(largestJointDistance(loaded.motion, reread) < 1e-6);
    CHECK(reread.frameTime() == Approx(loaded.motion.frameTime()).epsilon(1e-9));
  }
}

TEST_CASE("a written BVH reads back to itself: channels equal to 1e-6 and bone lengths constant", "[bvh][data]") {
  const Motion m = test::loadMocap("cmu/bvh/13_18_boxing.bvh").motion;
  std::ostringstream first;
  writeBvh(first, m);
  const Motion reread = parseBvh(first.str(), "first.bvh");
  std::ostringstream second;
  writeBvh(second, reread);
  const auto a = channelValues(first.str()), b = channelValues(second.str());
  REQUIRE(a.size() == b.size());
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  CHECK(worst < 1e-6);

  const std::size_t n = reread.skeleton().jointCount();
  const auto p = jointPositions(reread);
  for (std::size_t j = 1; j < n; ++j) {
    const auto parent = static_cast<std::size_t>(reread.skeleton().joint(j).parent);
    double lo = 1e9, hi = 0;
    for (std::size_t f = 0; f < reread.frameCount(); ++f) {
      const double length = (p[f * n + j] - p[f * n + parent]).norm();
      lo = std::min(lo, length);
      hi = std::max(hi, length);
    }
    CHECK(hi - lo < 1e-9);
  }
}

TEST_CASE("an ASF/AMC motion exports to BVH with the same joint positions", "[bvh][asf][data]") {
  const Motion m = test::loadMocap("cmu/asfamc/13_17.amc").motion.slice(0, 600);
  std::ostringstream out;
  writeBvh(out, m);
  const Motion reread = parseBvh(out.str(), "exported.bvh");
  CHECK(reread.skeleton().jointCount() == m.skeleton().jointCount());
  CHECK(largestJointDistance(m, reread) < 1e-6);
}

}  // namespace bvh_roundtrip_test
