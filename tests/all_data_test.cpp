#include <sstream>

#include <catch2/catch.hpp>

#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace all_data_test {

using namespace mgrl;

TEST_CASE("every motion file in the data folder loads, annotates and survives a BVH round trip", "[.slow][data]") {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(test::mocap())) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".bvh" || ext == ".amc") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() >= 40);
  for (const auto& file : files) {
    CAPTURE(file.string());
    const LoadedMotion loaded = loadMotion(file);
    const Motion& m = loaded.motion;
    const SkeletonRoles roles = findRoles(m.skeleton());
    CHECK(roles.restHeight > 1.4);
    CHECK(roles.restHeight < 2.0);
    const Annotation a = annotate(m, roles);
    CHECK(a.contact[0].size() == m.frameCount());
    for (const EffectiveHit& hit : a.hits) CHECK(hit.speed_mps < AnnotationParams{}.punchMaxSpeed_mps);

    std::ostringstream out;
    writeBvh(out, m);
    const Motion back = parseBvh(out.str(), "roundtrip.bvh");
    const auto p = jointPositions(m), q = jointPositions(back);
    REQUIRE(p.size() == q.size());
    double worst = 0;
    for (std::size_t i = 0; i < p.size(); ++i) worst = std::max(worst, (p[i] - q[i]).norm());
    CHECK(worst < 1e-6);
  }
}

}  // namespace all_data_test
