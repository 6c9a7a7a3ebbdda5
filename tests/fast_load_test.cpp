// What makes commands start quickly (issue 20): files hashed a block at a time, bundle
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

#include "graph_command.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/huge_pages.hpp"
#include "mgrl/core/npy.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "test_support.hpp"

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
  mgrl::app::GraphOptions options;
  options.cacheDir = tmp.path;
  options.motion = false;
  const mgrl::app::GraphResult built = mgrl::app::obtainGraph(scenario, options);
  REQUIRE_FALSE(built.fromCache);
  REQUIRE(built.db.skeleton);  // building needs the capture

  const mgrl::app::GraphResult cached = mgrl::app::obtainGraph(scenario, options);
  REQUIRE(cached.fromCache);
  CHECK_FALSE(cached.db.skeleton);
  CHECK(cached.db.clips.empty());
  options.motion = true;
  const mgrl::app::GraphResult posed = mgrl::app::obtainGraph(scenario, options);
  REQUIRE(posed.fromCache);
  REQUIRE(posed.db.skeleton);
  CHECK(posed.db.clips.size() == 1);
  for (const mgrl::app::GraphResult* g : {&cached, &posed}) {
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
  const mgrl::app::GraphResult older = mgrl::app::obtainGraph(scenario, options);
  REQUIRE(older.fromCache);
  CHECK(older.db.skeleton);
  CHECK(older.travel.clipTravel_m == built.travel.clipTravel_m);
  CHECK(older.travel.clip == built.travel.clip);
}
