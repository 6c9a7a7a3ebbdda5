#include <catch2/catch.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/units.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace units_test {

using namespace mgrl;

TEST_CASE("units are detected from a plausible standing height", "[units]") {
  CHECK(detectLengthUnit(1.75, "x") == LengthUnit::Metre);
  CHECK(detectLengthUnit(168.0, "x") == LengthUnit::Centimetre);
  CHECK(detectLengthUnit(66.0, "x") == LengthUnit::Inch);
  CHECK(detectLengthUnit(1.63 / 0.05644, "x") == LengthUnit::Cmu);
  CHECK_THROWS_WITH(detectLengthUnit(1e6, "huge.bvh"), Catch::Contains("huge.bvh") && Catch::Contains("--units"));
}

TEST_CASE("unit names parse, and a wrong one lists the choices", "[units]") {
  CHECK(parseLengthUnit("cmu") == LengthUnit::Cmu);
  CHECK(metresPer(LengthUnit::Inch) == Approx(0.0254));
  CHECK(metresPer(LengthUnit::Cmu) == Approx(0.05644).epsilon(1e-3));
  CHECK_THROWS_WITH(parseLengthUnit("furlong"), Catch::Contains("expected one of auto, m, cm, inch, cmu, found 'furlong'"));
}

TEST_CASE("real files load in metres with the right detected units", "[units][data]") {
  const LoadedMotion cmu = test::loadMocap("cmu/bvh/13_17_boxing.bvh");
  CHECK(cmu.units == LengthUnit::Cmu);
  const LoadedMotion snu = test::loadMocap("snu_martial_arts/motion/s_001_3_1.bvh");
  CHECK(snu.units == LengthUnit::Centimetre);
  // SNU's root OFFSET duplicates its absolute position channels: the channels must win,
  // so the pelvis stays about 1 m up, not 2.
  CHECK(snu.motion.localTranslation(0, 0).y() == Approx(0.95).margin(0.15));
  LoadOptions forced;
  forced.units = LengthUnit::Metre;
  const LoadedMotion raw = test::loadMocap("cmu/bvh/13_17_boxing.bvh", forced);
  CHECK(raw.motion.skeleton().joint(2).offset.norm() ==
        Approx(cmu.motion.skeleton().joint(2).offset.norm() / metresPer(LengthUnit::Cmu)));
}

}  // namespace units_test
