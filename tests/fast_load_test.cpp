// What makes commands start quickly: files hashed a block at a time, bundle
// arrays read in place from a mapping, big tables on huge pages, and a cached graph that
// needs no capture parsed. Each must give exactly what the slow way gave.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "builtin_plugins.hpp"
#include "graph_command.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/huge_pages.hpp"
#include "mgrl/core/npy.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace fast_load_test {

namespace fs = std::filesystem;
using Catch::Contains;

namespace {

void writeBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Bytes that are not all alike, of any length.
std::string pattern(std::size_t n) {
  std::string bytes(n, '\0');
  std::uint32_t x = 12345;
  for (char& c : bytes) {
    x = x * 1664525u + 1013904223u;
    c = static_cast<char>(x >> 24);
  }
  return bytes;
}

}  // namespace

TEST_CASE("hashFileContents hashes a file as update(readFile(path)) does, whatever its size", "[fast_load][hash]") {
  mgrl::test::TempDir tmp("fast-load-test");
  // Empty, smaller than a stripe, and on and across the 64 KB read blocks.
  for (std::size_t n : {std::size_t{0}, std::size_t{5}, std::size_t{1} << 16, (std::size_t{1} << 16) + 7,
                        std::size_t{1} << 20, (std::size_t{1} << 20) + 33, std::size_t{3} << 20}) {
    CAPTURE(n);
    const fs::path file = tmp.path / "data.bin";
    writeBytes(file, pattern(n));
    mgrl::Hasher whole, streamed;
    whole.update(std::string_view("before"));
    streamed.update(std::string_view("before"));
    whole.update(std::string_view(mgrl::readFile(file)));
    mgrl::hashFileContents(streamed, file);
    CHECK(streamed.value() == whole.value());
    // One byte changed anywhere changes it.
    if (n > 0) {
      std::string changed = pattern(n);
      changed[n / 2] = static_cast<char>(changed[n / 2] ^ 1);
      writeBytes(file, changed);
      mgrl::Hasher other;
      other.update(std::string_view("before"));
      mgrl::hashFileContents(other, file);
      CHECK(other.value() != whole.value());
    }
  }
}

TEST_CASE("hashFileContents and MappedFile say which file is missing or not a file", "[fast_load][hash]") {
  mgrl::test::TempDir tmp("fast-load-test");
  mgrl::Hasher h;
  CHECK_THROWS_WITH(mgrl::hashFileContents(h, tmp.path / "none.bvh"), Contains("none.bvh: cannot open"));
  CHECK_THROWS_WITH(mgrl::hashFileContents(h, tmp.path), Contains("expected a file, found a directory"));
  CHECK_THROWS_WITH(mgrl::MappedFile(tmp.path / "none.npy"), Contains("none.npy: cannot open"));
  CHECK_THROWS_WITH(mgrl::MappedFile(tmp.path), Contains("expected a regular file, found a directory"));
  CHECK_THROWS_WITH(mgrl::MappedFile("/dev/null"), Contains("/dev/null: expected a regular file, found a device"));
}

TEST_CASE("MappedFile gives a file's bytes, and none for an empty file", "[fast_load]") {
  mgrl::test::TempDir tmp("fast-load-test");
  const std::string bytes = pattern(10000);
  writeBytes(tmp.path / "a.bin", bytes);
  writeBytes(tmp.path / "empty.bin", "");
  const mgrl::MappedFile mapped(tmp.path / "a.bin");
  CHECK(mapped.bytes() == bytes);
  CHECK(mgrl::MappedFile(tmp.path / "empty.bin").bytes().empty());
}

TEST_CASE("npyView reads an aligned array in place, with npyDecode's checks", "[fast_load][npy]") {
  const std::vector<float> values = {1.5f, -2.0f, 3.25f, 0.0f, 7.0f, 1e-30f};
  const std::string file = mgrl::npyEncode<float>(values, {2, 3});
  // A copy at an address aligned for floats (the encoder puts the data at 64 bytes).
  std::vector<float> storage(file.size() / sizeof(float) + 1);
  std::memcpy(storage.data(), file.data(), file.size());
  const std::string_view bytes(reinterpret_cast<const char*>(storage.data()), file.size());
  std::vector<std::size_t> shape;
  const auto view = mgrl::npyView<float>(bytes, "a.npy", &shape);
  REQUIRE(view.has_value());
  CHECK(shape == std::vector<std::size_t>{2, 3});
  CHECK(std::vector<float>(view->begin(), view->end()) == values);
  CHECK(reinterpret_cast<const char*>(view->data()) >= bytes.data());
  CHECK(reinterpret_cast<const char*>(view->data()) < bytes.data() + bytes.size());
  // Misaligned data is not viewed (the caller decodes a copy instead).
  const std::string shifted = " " + file;
  REQUIRE(reinterpret_cast<std::uintptr_t>(shifted.data()) % alignof(float) == 0);
  CHECK_FALSE(mgrl::npyView<float>(std::string_view(shifted).substr(1), "a.npy").has_value());
  // The same refusals as npyDecode.
  CHECK_THROWS_WITH(mgrl::npyView<double>(bytes, "a.npy"), Contains("a.npy") && Contains("descr '<f8'"));
  CHECK_THROWS_WITH(mgrl::npyView<float>(bytes.substr(0, bytes.size() - 4), "a.npy"),
                    Contains("24 data bytes for shape (2, 3)"));
}

TEST_CASE("HugePageAllocator gives zeroed, aligned, usable blocks, small and large", "[fast_load]") {
  std::vector<float, mgrl::HugePageAllocator<float>> small(100, 0.0f), large((std::size_t{5} << 20) / 4 + 7);
  CHECK(reinterpret_cast<std::uintptr_t>(large.data()) % mgrl::huge_pages::kHugePage == 0);
  CHECK(std::all_of(large.begin(), large.end(), [](float v) { return v == 0.0f; }));
  for (std::size_t i = 0; i < large.size(); i += 4099) large[i] = static_cast<float>(i);
  large.back() = 1.0f;
  small[99] = 2.0f;
  auto copy = large;  // copies through the allocator
  CHECK(copy == large);
  large.resize(10);  // a small block again after a large one
  large.shrink_to_fit();
  CHECK(large.size() == 10);
  CHECK(copy.back() == 1.0f);
  CHECK(small[99] == 2.0f);
  mgrl::HugePageAllocator<double> huge;
  CHECK_THROWS_AS(huge.allocate(std::numeric_limits<std::size_t>::max() / 4), std::bad_array_new_length);
}

TEST_CASE("a cached graph needs no capture parsed unless poses are wanted, and measures the same travel",
          "[fast_load][graph_cache][data]") {
  mgrl::test::TempDir tmp("fast-load-test");
  const mgrl::Scenario scenario = mgrl::parseScenario(
      "name: mini\nmotion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n  fps: 30\ngraph:\n  threshold: 0.4\n"
      "behaviors:\n  approach:\n    discretizer: {type: polar2d, radius: 3, rings: 4, sectors: 8}\n"
      "    reward: {type: approach}\n    learner: {type: value_iteration}\n",
      fs::path(MGRL_SOURCE_DIR) / "scenarios" / "test.yaml", mgrl::test::mocap());
  mgrl::GraphOptions options;
  options.plugins = &mgrl::builtinPlugins();
  options.cacheDir = tmp.path;
  options.motion = false;
  const mgrl::GraphResult built = mgrl::obtainGraph(scenario, options);
  REQUIRE_FALSE(built.fromCache);
  REQUIRE(built.db.skeleton);  // building needs the capture

  const mgrl::GraphResult cached = mgrl::obtainGraph(scenario, options);
  REQUIRE(cached.fromCache);
  CHECK_FALSE(cached.db.skeleton);
  CHECK(cached.db.clips.empty());
  options.motion = true;
  const mgrl::GraphResult posed = mgrl::obtainGraph(scenario, options);
  REQUIRE(posed.fromCache);
  REQUIRE(posed.db.skeleton);
  CHECK(posed.db.clips.size() == 1);
  for (const mgrl::GraphResult* g : {&cached, &posed}) {
    CHECK(g->travel.clipTravel_m == built.travel.clipTravel_m);
    CHECK(g->travel.clip == built.travel.clip);
    CHECK(g->travel.rootExtent_m == built.travel.rootExtent_m);
    CHECK(g->travel.walkTravel_m == built.travel.walkTravel_m);
    REQUIRE(g->travel.reaches.size() == 1);
    CHECK(g->travel.reaches[0].reach_m == built.travel.reaches[0].reach_m);
  }
  CHECK(built.travel.clipTravel_m > 0.1);

  // A bundle made before it kept capture_travel: the capture is parsed for it, as before.
  const fs::path manifestPath = built.bundle / "manifest.json";
  nlohmann::json manifest = nlohmann::json::parse(mgrl::readFile(manifestPath));
  REQUIRE(manifest["provenance"].contains("capture_travel"));
  manifest["provenance"].erase("capture_travel");
  manifest["hash"] = mgrl::manifestHash(manifest);
  writeBytes(manifestPath, manifest.dump(2));
  options.motion = false;
  const mgrl::GraphResult older = mgrl::obtainGraph(scenario, options);
  REQUIRE(older.fromCache);
  CHECK(older.db.skeleton);
  CHECK(older.travel.clipTravel_m == built.travel.clipTravel_m);
  CHECK(older.travel.clip == built.travel.clip);
}

namespace {

// Every value a posed avatar is made from: the skeletons, the motions bit for bit, and the
// annotations computed on them.
void requireSameDatabase(const mgrl::MotionDatabase& a, const mgrl::MotionDatabase& b) {
  REQUIRE(a.skeleton);
  REQUIRE(b.skeleton);
  CHECK(a.frameTime == b.frameTime);
  CHECK(a.offsets == b.offsets);
  CHECK(a.roles.fist == b.roles.fist);
  CHECK(a.roles.fistTipOffset == b.roles.fistTipOffset);
  CHECK(a.roles.restHeight == b.roles.restHeight);
  REQUIRE(a.clips.size() == b.clips.size());
  for (std::size_t c = 0; c < a.clips.size(); ++c) {
    CAPTURE(c);
    const mgrl::Clip& x = a.clips[c];
    const mgrl::Clip& y = b.clips[c];
    CHECK(x.name == y.name);
    CHECK(x.path == y.path);
    const mgrl::Skeleton& sx = x.motion.skeleton();
    const mgrl::Skeleton& sy = y.motion.skeleton();
    REQUIRE(sx.jointCount() == sy.jointCount());
    for (std::size_t j = 0; j < sx.jointCount(); ++j) {
      CAPTURE(j);
      CHECK(sx.joint(j).name == sy.joint(j).name);
      CHECK(sx.joint(j).parent == sy.joint(j).parent);
      CHECK(sx.joint(j).offset == sy.joint(j).offset);
      CHECK(sx.joint(j).channels == sy.joint(j).channels);
      CHECK(sx.joint(j).endSite == sy.joint(j).endSite);
    }
    REQUIRE(x.motion.frameCount() == y.motion.frameCount());
    CHECK(x.motion.frameTime() == y.motion.frameTime());
    std::size_t differing = 0;
    for (std::size_t f = 0; f < x.motion.frameCount(); ++f) {
      for (std::size_t j = 0; j < sx.jointCount(); ++j)
        differing += x.motion.rotation(f, j).coeffs() != y.motion.rotation(f, j).coeffs();
      const auto tx = x.motion.translations(f), ty = y.motion.translations(f);
      REQUIRE(tx.size() == ty.size());
      for (std::size_t t = 0; t < tx.size(); ++t) differing += tx[t] != ty[t];
    }
    CHECK(differing == 0);
    const mgrl::Annotation& p = x.annotation;
    const mgrl::Annotation& q = y.annotation;
    CHECK(p.groundY == q.groundY);
    CHECK(p.contact == q.contact);
    CHECK(p.punches == q.punches);
    CHECK(p.kickCount == q.kickCount);
    CHECK(p.standingHeight == q.standingHeight);
    REQUIRE(p.hits.size() == q.hits.size());
    for (std::size_t h = 0; h < p.hits.size(); ++h) {
      CHECK(p.hits[h].frame == q.hits[h].frame);
      CHECK(p.hits[h].tipWorld == q.hits[h].tipWorld);
      CHECK(p.hits[h].speed_mps == q.hits[h].speed_mps);
    }
    REQUIRE(p.frames.size() == q.frames.size());
    for (std::size_t f = 0; f < p.frames.size(); ++f) differing += p.frames[f].origin != q.frames[f].origin || p.frames[f].yaw != q.frames[f].yaw;
    CHECK(differing == 0);
  }
}

}  // namespace

TEST_CASE("a cached graph poses avatars from the capture it keeps, exactly as parsing it again would",
          "[fast_load][graph_cache][data]") {
  mgrl::test::TempDir tmp("fast-load-test");
  const mgrl::Scenario scenario = mgrl::parseScenario(
      "name: mini\nmotion:\n  files: [cmu/bvh/13_17_boxing.bvh, cmu/bvh/13_18_boxing.bvh]\n  fps: 30\n"
      "graph:\n  threshold: 0.4\nbehaviors:\n  approach:\n    discretizer: {type: polar2d, radius: 3, rings: 4, "
      "sectors: 8}\n    reward: {type: approach}\n    learner: {type: value_iteration}\n",
      fs::path(MGRL_SOURCE_DIR) / "scenarios" / "test.yaml", mgrl::test::mocap());
  mgrl::GraphOptions options;
  options.plugins = &mgrl::builtinPlugins();
  options.cacheDir = tmp.path;
  const mgrl::GraphResult built = mgrl::obtainGraph(scenario, options);
  REQUIRE_FALSE(built.fromCache);
  const nlohmann::json manifest = nlohmann::json::parse(mgrl::readFile(built.bundle / "manifest.json"));
  REQUIRE(manifest.contains("motion"));
  CHECK(manifest["motion"]["clips"].size() == 2);
  CHECK(manifest["arrays"].contains("motion_rotations"));
  // The graph walk of the travel check is the model's own: kept, not walked again.
  CHECK(manifest["provenance"]["capture_travel"]["walk_travel_m"] == built.travel.walkTravel_m);
  CHECK(manifest["provenance"]["capture_travel"]["action_travel_m"] == built.travel.actionTravel_m);

  const mgrl::GraphResult cached = mgrl::obtainGraph(scenario, options);
  REQUIRE(cached.fromCache);
  requireSameDatabase(cached.db, built.db);
  CHECK(cached.travel.walkTravel_m == built.travel.walkTravel_m);
  CHECK(cached.travel.actionTravel_m == built.travel.actionTravel_m);
  CHECK(cached.travel.reaches.size() == built.travel.reaches.size());

  SECTION("a bundle saved without the motion: the capture is parsed, as before") {
    nlohmann::json edited = manifest;
    edited.erase("motion");
    edited["arrays"].erase("motion_rotations");
    edited["arrays"].erase("motion_translations");
    edited["hash"] = mgrl::manifestHash(edited);
    writeBytes(built.bundle / "manifest.json", edited.dump(2));
    const mgrl::GraphResult parsed = mgrl::obtainGraph(scenario, options);
    REQUIRE(parsed.fromCache);
    requireSameDatabase(parsed.db, built.db);
  }
  SECTION("a damaged motion array: the bundle is rebuilt, not trusted") {
    std::string bytes = mgrl::readFile(built.bundle / "motion_rotations.npy");
    bytes[bytes.size() / 2] ^= 0x10;
    writeBytes(built.bundle / "motion_rotations.npy", bytes);
    std::vector<std::string> log;
    options.log = [&](const std::string& m) { log.push_back(m); };
    const mgrl::GraphResult rebuilt = mgrl::obtainGraph(scenario, options);
    CHECK_FALSE(rebuilt.fromCache);
    REQUIRE_FALSE(log.empty());
    CHECK_THAT(log.front(), Contains("graph: cache is damaged, rebuilding") && Contains("motion_rotations.npy") &&
                                Contains("the file was altered"));
    requireSameDatabase(rebuilt.db, built.db);
  }
}

}  // namespace fast_load_test
