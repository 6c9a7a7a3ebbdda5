// The graph cache bundle: a hand-built state-action model round-trips through
// saveGraphBundle/loadGraphBundle exactly and reproducibly; every way a bundle can be stale
// or damaged is reported, never trusted; checkModel names the broken array. Also the
// content hash the bundle relies on (XXH64, checked against the reference digests).

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "builtin_plugins.hpp"
#include "graph_command.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/npy.hpp"
#include "mgrl/graph/graph_cache.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/motion/roles.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace graph_cache_test {

namespace fs = std::filesystem;
using Catch::Contains;
using mgrl::GraphBundleLoad;
using mgrl::StateActionModel;
using nlohmann::json;

namespace {

// Two clips of 10 frames; states at frames 2, 8 and 14; four actions, three of which go
// through a transition edge; four hits.
//   a0: s0 -> s1  frames 3 4 5 6 7 8        (clip 0 played on)
//   a1: s0 -> s2  frames 3 4 | 13 14        (transition 4 -> 13)
//   a2: s1 -> s2  frames 9 | 12 13 14       (transition 9 -> 12)
//   a3: s2 -> s0  frames 15 16 | 1 2        (transition 16 -> 1)
StateActionModel tinyModel() {
  StateActionModel m;
  m.frameTime = 1.0 / 30;
  m.framesTotal = 20;
  m.clipOffset = {0, 10, 20};
  for (std::uint32_t f = 1; f <= 16; ++f) m.componentFrames.push_back(f);
  m.transitions = {4, 13, 9, 12, 16, 1};
  m.transitionDistance = {0.5f, 0.25f, 0.75f};
  m.stateFrame = {2, 8, 14};
  m.actionFrom = {0, 0, 1, 2};
  m.actionTo = {1, 2, 2, 0};
  m.actionFrameBegin = {0, 6, 10, 14, 18};
  for (int a = 0; a < 4; ++a)
    m.actionDisplacement.insert(m.actionDisplacement.end(), {0.1 * (a + 1), -0.2 * (a + 1), 0.3 / (a + 1)});
  m.stateActionBegin = {0, 2, 3, 4};
  m.actionFrames = {3, 4, 5, 6, 7, 8, 3, 4, 13, 14, 9, 12, 13, 14, 15, 16, 1, 2};
  for (std::size_t i = 0; i < 3 * m.actionFrames.size(); ++i) {
    m.frameRoot.push_back(0.01 * static_cast<double>(i) - 0.2);
    m.frameCentroid.push_back(1.0f / static_cast<float>(i + 3));
  }
  m.frameEntersTransition.assign(m.actionFrames.size(), 0);
  for (std::size_t i : {8, 11, 16}) m.frameEntersTransition[i] = 1;
  m.hits = {{0, 4, 1, 0.1f, 1.2f, 0.6f, 1.0f},
            {1, 2, 0, -0.3f, 1.1f, 0.5f, 0.5f},
            {1, 3, 1, 0.2f, 1.3f, 0.7f, 0.75f},
            {3, 1, 0, 0.0f, 1.0f, 0.4f, 0.25f}};
  m.actionHitBegin = {0, 1, 3, 3, 4};
  m.centroid[0] = 0.1;
  m.centroid[1] = 1.2;
  m.centroid[2] = 0.35;
  m.maxHitSpeed_mps = 7.25;
  m.kicks = {{2, 2, 1, 0.3f, 0.9f, 0.8f, 1.0f}};
  m.actionKickBegin = {0, 0, 0, 1, 1};
  m.maxKickSpeed_mps = 9.5;
  // Two joints; every role is one of them.
  m.jointNames = {"Hips", "LeftHand"};
  for (std::size_t r = 0; r < mgrl::roleNames().size(); ++r) m.roleJoint.push_back(r % 2 == 0 ? 1 : 0);
  for (std::uint32_t i = 0; i < 2 * m.framesTotal; ++i) {
    m.sourceJoint.insert(m.sourceJoint.end(), {0.01f * static_cast<float>(i), 1.0f, 0.25f});
    m.sourceJointSpeed.push_back(0.5f * static_cast<float>(i % 3));
  }
  return m;
}

json provenance(const std::string& key) {
  return {{"key", key}, {"scenario", "boxing.yaml"}, {"seed", 7}};
}

void requireSameModel(const StateActionModel& a, const StateActionModel& b) {
  CHECK(a.frameTime == b.frameTime);
  CHECK(a.framesTotal == b.framesTotal);
  CHECK(a.clipOffset == b.clipOffset);
  CHECK(a.componentFrames == b.componentFrames);
  CHECK(a.transitions == b.transitions);
  CHECK(a.transitionDistance == b.transitionDistance);
  CHECK(a.stateFrame == b.stateFrame);
  CHECK(a.actionFrom == b.actionFrom);
  CHECK(a.actionTo == b.actionTo);
  CHECK(a.actionFrameBegin == b.actionFrameBegin);
  CHECK(a.actionDisplacement == b.actionDisplacement);
  CHECK(a.stateActionBegin == b.stateActionBegin);
  CHECK(a.actionFrames == b.actionFrames);
  CHECK(a.frameRoot == b.frameRoot);
  CHECK(a.frameCentroid == b.frameCentroid);
  CHECK(a.frameEntersTransition == b.frameEntersTransition);
  CHECK(a.actionHitBegin == b.actionHitBegin);
  CHECK(a.actionKickBegin == b.actionKickBegin);
  CHECK(a.maxKickSpeed_mps == b.maxKickSpeed_mps);
  CHECK(a.jointNames == b.jointNames);
  CHECK(a.roleJoint == b.roleJoint);
  CHECK(a.sourceJoint == b.sourceJoint);
  CHECK(a.sourceJointSpeed == b.sourceJointSpeed);
  REQUIRE(a.kicks.size() == b.kicks.size());
  for (std::size_t k = 0; k < a.kicks.size(); ++k) {
    CAPTURE(k);
    CHECK(a.kicks[k].action == b.kicks[k].action);
    CHECK(a.kicks[k].offset == b.kicks[k].offset);
    CHECK(a.kicks[k].hand == b.kicks[k].hand);
    CHECK(a.kicks[k].x == b.kicks[k].x);
    CHECK(a.kicks[k].weight == b.kicks[k].weight);
  }
  REQUIRE(a.hits.size() == b.hits.size());
  for (std::size_t h = 0; h < a.hits.size(); ++h) {
    CAPTURE(h);
    CHECK(a.hits[h].action == b.hits[h].action);
    CHECK(a.hits[h].offset == b.hits[h].offset);
    CHECK(a.hits[h].hand == b.hits[h].hand);
    CHECK(a.hits[h].x == b.hits[h].x);
    CHECK(a.hits[h].y == b.hits[h].y);
    CHECK(a.hits[h].z == b.hits[h].z);
    CHECK(a.hits[h].weight == b.hits[h].weight);
  }
  for (int k = 0; k < 3; ++k) CHECK(a.centroid[k] == b.centroid[k]);
  CHECK(a.maxHitSpeed_mps == b.maxHitSpeed_mps);
}

void writeBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  REQUIRE(out.good());
}

std::map<std::string, std::string> filesIn(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir))
    files[entry.path().filename().string()] = mgrl::readFile(entry.path());
  return files;
}

std::vector<std::string> namesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Loads with the key the bundle was saved with and requires Damaged with `reason`.
void requireDamaged(const fs::path& bundle, const std::string& reason) {
  const GraphBundleLoad load = mgrl::loadGraphBundle(bundle, "k1");
  CAPTURE(load.reason);
  REQUIRE(load.status == GraphBundleLoad::Damaged);
  REQUIRE_THAT(load.reason, Contains(reason));
  REQUIRE(load.model.actionFrames.empty());
}

}  // namespace

// --- hash -------------------------------------------------------------------------------

TEST_CASE("hashBytes is XXH64 with seed 0", "[graph_cache][hash]") {
  // Reference digests from the xxhash library.
  REQUIRE(mgrl::hashBytes("") == 0xef46db3751d8e999ULL);
  REQUIRE(mgrl::hashBytes("a") == 0xd24ec4f1a98c6e5bULL);
  REQUIRE(mgrl::hashBytes("abc") == 0x44bc2cf5ad770999ULL);
  REQUIRE(mgrl::hashBytes("The quick brown fox jumps over the lazy dog") == 0x0b242d361fda71bcULL);
  REQUIRE(mgrl::Hasher().hex() == "ef46db3751d8e999");
  REQUIRE(mgrl::hexDigest(0xabcULL) == "0000000000000abc");
}

TEST_CASE("Hasher gives the same digest however the bytes are split", "[graph_cache][hash]") {
  std::string bytes;
  for (int copy = 0; copy < 3; ++copy)
    for (int b = 0; b < 256; ++b) bytes.push_back(static_cast<char>(b));
  bytes += "xyz";
  REQUIRE(mgrl::hashBytes(bytes) == 0xe921a1b45bd779f8ULL);
  for (std::size_t step : {1, 3, 7, 8, 31, 32, 33, 100}) {
    CAPTURE(step);
    mgrl::Hasher h;
    for (std::size_t at = 0; at < bytes.size(); at += step) h.updateBytes(std::string_view(bytes).substr(at, step));
    REQUIRE(h.value() == 0xe921a1b45bd779f8ULL);
  }
}

TEST_CASE("Hasher length-prefixes strings and encodes numbers little-endian", "[graph_cache][hash]") {
  mgrl::Hasher abc;
  abc.update(std::string_view("ab")).update(std::string_view("c"));
  mgrl::Hasher split;
  split.update(std::string_view("a")).update(std::string_view("bc"));
  REQUIRE(abc.value() != split.value());
  REQUIRE(abc.value() == 0x7b92a14fbcbf0536ULL);  // XXH64 of le64(2) "ab" le64(1) "c"
  mgrl::Hasher numbers;
  numbers.update(std::int64_t{-1}).update(1.5);
  REQUIRE(numbers.hex() == "c2aa4fae55a97f28");  // XXH64 of le64(-1) le64(bits of 1.5)
  // Other integer types go through int64.
  REQUIRE(mgrl::Hasher().update(7).value() == mgrl::Hasher().update(std::int64_t{7}).value());
  REQUIRE(mgrl::Hasher().update(0.0).value() != mgrl::Hasher().update(-0.0).value());
}

// --- checkModel -------------------------------------------------------------------------

TEST_CASE("checkModel accepts the hand-built model", "[graph_cache]") {
  REQUIRE_NOTHROW(mgrl::checkModel(tinyModel(), "tiny"));
}

TEST_CASE("checkModel names the array and index that break an invariant", "[graph_cache]") {
  StateActionModel m = tinyModel();
  std::string message;
  SECTION("frame time") {
    m.frameTime = 0;
    message = "tiny: frameTime: expected a finite number of seconds above 0, found 0";
  }
  SECTION("size of actionTo") {
    m.actionTo.pop_back();
    message = "tiny: actionTo: expected 4 entries (one per action, as actionFrom), found 3";
  }
  SECTION("size of frameCentroid") {
    m.frameCentroid.push_back(0);
    message = "tiny: frameCentroid: expected 54 entries";
  }
  SECTION("odd transitions") {
    m.transitions.push_back(3);
    message = "tiny: transitions: expected an even number of entries";
  }
  SECTION("clipOffset not starting at 0") {
    m.clipOffset[0] = 1;
    message = "tiny: clipOffset[0]: expected 0, found 1";
  }
  SECTION("clipOffset not ending at framesTotal") {
    m.clipOffset[2] = 19;
    message = "tiny: clipOffset[2]: expected framesTotal = 20 (the end), found 19";
  }
  SECTION("stateActionBegin decreasing") {
    m.stateActionBegin = {0, 3, 2, 4};
    message = "tiny: stateActionBegin[2]: expected at least stateActionBegin[1] = 3, found 2";
  }
  SECTION("action frame out of range") {
    m.actionFrames[5] = 20;
    message = "tiny: actionFrames[5]: expected a frame below framesTotal 20, found 20";
  }
  SECTION("action without frames") {
    m.actionFrameBegin = {0, 6, 6, 14, 18};
    message = "tiny: actionFrameBegin[2]: expected above actionFrameBegin[1] = 6 (every action has a frame)";
  }
  SECTION("action not ending on its end state's frame") {
    m.actionFrames[9] = 15;
    message = "tiny: actionFrames[9]: expected frame 14 of state 2 (action 1 ends there), found 15";
  }
  SECTION("state out of range") {
    m.actionTo[3] = 3;
    message = "tiny: actionTo[3]: expected a state below stateCount 3, found 3";
  }
  SECTION("actionFrom disagreeing with stateActionBegin") {
    m.actionFrom = {0, 1, 1, 2};
    message = "tiny: actionFrom[1]: expected state 0";
  }
  SECTION("stateFrame not ascending") {
    m.stateFrame = {2, 2, 14};
    message = "tiny: stateFrame[1]: expected above stateFrame[0] = 2 (strictly ascending), found 2";
  }
  SECTION("componentFrames not ascending") {
    std::swap(m.componentFrames[3], m.componentFrames[4]);
    message = "tiny: componentFrames[4]";
  }
  SECTION("transitions unsorted") {
    m.transitions = {9, 12, 4, 13, 16, 1};
    message = "tiny: transitions[2]: expected pairs sorted, at least (9, 12), found (4, 13)";
  }
  SECTION("hit offset past its action") {
    m.hits[1].offset = 5;
    message = "tiny: hits[1].offset: expected an offset in [1, 4] (the length of action 1), found 5";
  }
  SECTION("hit offset 0") {
    m.hits[0].offset = 0;
    message = "tiny: hits[0].offset";
  }
  SECTION("hit in the wrong action") {
    m.hits[3].action = 2;
    message = "tiny: hits[3].action: expected 3 (actionHitBegin), found 2";
  }
  SECTION("hand") {
    m.hits[0].hand = 2;
    message = "tiny: hits[0].hand: expected 0 (left) or 1 (right), found 2";
  }
  SECTION("kick offset") {
    m.kicks[0].offset = 9;
    message = "tiny: kicks[0].offset: expected an offset in [1, 4] (the length of action 2), found 9";
  }
  SECTION("kick begin size") {
    m.actionKickBegin.pop_back();
    message = "tiny: actionKickBegin: expected 5 entries (actions + 1), found 4";
  }
  SECTION("hit weight") {
    m.hits[2].weight = 0;
    message = "tiny: hits[2].weight: expected a weight in (0, 1], found 0";
  }
  SECTION("non-finite root") {
    m.frameRoot[7] = std::nan("");
    message = "tiny: frameRoot[7]: expected a finite number, found nan";
  }
  SECTION("non-finite hit position") {
    m.hits[2].y = INFINITY;
    message = "tiny: hits[2].y: expected a finite number, found inf";
  }
  SECTION("frameEntersTransition flag") {
    m.frameEntersTransition[3] = 2;
    message = "tiny: frameEntersTransition[3]: expected 0 or 1, found 2";
  }
  SECTION("joint positions not sized by the joints") {
    m.sourceJoint.pop_back();
    message = "tiny: sourceJoint: expected 120 entries (3 per source frame and joint), found 119";
  }
  SECTION("a role's joint out of range") {
    m.roleJoint[3] = 2;
    message = "tiny: roleJoint[3]: expected a joint in [-1, 2), found 2";
  }
  SECTION("roles without joints") {
    m.jointNames.clear();
    m.sourceJoint.clear();
    m.sourceJointSpeed.clear();
    message = "tiny: roleJoint[0]: expected a joint in [-1, 0), found 1";
  }
  SECTION("a negative joint speed") {
    m.sourceJointSpeed[5] = -1;
    message = "tiny: sourceJointSpeed[5]: expected a finite speed of at least 0, found -1";
  }
  SECTION("an empty model") {
    m = StateActionModel{};
    m.frameTime = 0.01;
    message = "tiny: clipOffset: expected at least one entry, found none";
  }
  CAPTURE(message);
  REQUIRE_THROWS_AS(mgrl::checkModel(m, "tiny"), mgrl::Error);
  REQUIRE_THROWS_WITH(mgrl::checkModel(m, "tiny"), Contains(message));
}

// --- saving and loading -----------------------------------------------------------------

TEST_CASE("a graph bundle round-trips every field of the model", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  const StateActionModel model = tinyModel();
  mgrl::saveGraphBundle(bundle, model, provenance("k1"));

  const GraphBundleLoad load = mgrl::loadGraphBundle(bundle, "k1");
  CAPTURE(load.reason);
  REQUIRE(load.status == GraphBundleLoad::Ok);
  REQUIRE(load.reason.empty());
  requireSameModel(load.model, model);

  const json& manifest = load.manifest;
  REQUIRE(manifest["format"] == "mgrl.graph");
  REQUIRE(manifest["version"] == mgrl::kGraphFormatVersion);
  REQUIRE(manifest["provenance"] == provenance("k1"));
  REQUIRE(manifest["scalars"]["frames_total"] == 20);
  REQUIRE(manifest["arrays"].size() == 23);
  REQUIRE(manifest["scalars"]["joint_names"] == json::array({"Hips", "LeftHand"}));
  REQUIRE(manifest["arrays"]["source_joint"]["shape"] == json::array({40, 3}));
  REQUIRE(manifest["arrays"]["hits_index"]["shape"] == json::array({4, 3}));
  REQUIRE(manifest["arrays"]["hits_value"]["dtype"] == "<f4");
  REQUIRE(manifest["arrays"]["frame_root"]["shape"] == json::array({18, 3}));
  REQUIRE(manifest["arrays"]["frame_enters_transition"]["dtype"] == "|u1");

  // One .npy per array plus the manifest, each a plain NumPy file.
  REQUIRE(namesIn(bundle).size() == 24);
  std::vector<std::size_t> shape;
  const auto frames = mgrl::npyDecode<std::uint32_t>(mgrl::readFile(bundle / "action_frames.npy"), "f", &shape);
  REQUIRE(frames == model.actionFrames);
  REQUIRE(shape == std::vector<std::size_t>{18});
  REQUIRE(manifest["arrays"]["action_frames"]["hash"] ==
          mgrl::hexDigest(mgrl::hashBytes(mgrl::readFile(bundle / "action_frames.npy"))));
}

TEST_CASE("a graph bundle without hits or transitions round-trips", "[graph_cache]") {
  StateActionModel model = tinyModel();
  model.hits.clear();
  model.actionHitBegin.assign(model.actionCount() + 1, 0);
  mgrl::test::TempDir tmp("graph-cache-test");
  mgrl::saveGraphBundle(tmp.path / "graph", model, provenance("k1"));
  const GraphBundleLoad load = mgrl::loadGraphBundle(tmp.path / "graph/", "k1");
  CAPTURE(load.reason);
  REQUIRE(load.status == GraphBundleLoad::Ok);
  requireSameModel(load.model, model);
}

TEST_CASE("saving the same model twice writes byte-identical files", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  mgrl::saveGraphBundle(tmp.path / "a", tinyModel(), provenance("k1"));
  const auto first = filesIn(tmp.path / "a");
  mgrl::saveGraphBundle(tmp.path / "a", tinyModel(), provenance("k1"));
  mgrl::saveGraphBundle(tmp.path / "b", tinyModel(), provenance("k1"));
  REQUIRE(first.size() == 24);
  REQUIRE(filesIn(tmp.path / "a") == first);
  REQUIRE(filesIn(tmp.path / "b") == first);
}

TEST_CASE("saving over a bundle replaces it and leaves no temporary directory", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  StateActionModel other = tinyModel();
  other.frameTime = 1.0 / 120;
  other.frameRoot[0] = 42;
  mgrl::saveGraphBundle(bundle, other, provenance("k2"));

  REQUIRE(namesIn(tmp.path) == std::vector<std::string>{"graph"});
  const GraphBundleLoad load = mgrl::loadGraphBundle(bundle, "k2");
  CAPTURE(load.reason);
  REQUIRE(load.status == GraphBundleLoad::Ok);
  requireSameModel(load.model, other);
}

TEST_CASE("saveGraphBundle replaces an empty directory but refuses to delete anything else", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  fs::create_directories(tmp.path / "empty");
  mgrl::saveGraphBundle(tmp.path / "empty", tinyModel(), provenance("k1"));
  REQUIRE(mgrl::loadGraphBundle(tmp.path / "empty", "k1").status == GraphBundleLoad::Ok);

  fs::create_directories(tmp.path / "home");
  writeBytes(tmp.path / "home" / "notes.txt", "keep me");
  REQUIRE_THROWS_WITH(mgrl::saveGraphBundle(tmp.path / "home", tinyModel(), provenance("k1")),
                      Contains("not deleting it"));
  REQUIRE(mgrl::readFile(tmp.path / "home" / "notes.txt") == "keep me");

  writeBytes(tmp.path / "file", "x");
  REQUIRE_THROWS_WITH(mgrl::saveGraphBundle(tmp.path / "file", tinyModel(), provenance("k1")),
                      Contains("expected a graph bundle directory or nothing, found another kind of file"));
  REQUIRE(namesIn(tmp.path) == std::vector<std::string>{"empty", "file", "home"});
}

TEST_CASE("saveGraphBundle refuses an invalid model or provenance and writes nothing", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  StateActionModel broken = tinyModel();
  broken.actionFrames[0] = 99;
  REQUIRE_THROWS_WITH(mgrl::saveGraphBundle(tmp.path / "graph", broken, provenance("k1")),
                      Contains("actionFrames[0]: expected a frame below framesTotal 20, found 99"));
  REQUIRE_THROWS_WITH(mgrl::saveGraphBundle(tmp.path / "graph", tinyModel(), json{{"seed", 1}}),
                      Contains("provenance: expected an object with a string \"key\""));
  REQUIRE(namesIn(tmp.path).empty());
}

TEST_CASE("loadGraphBundle reports a missing bundle", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const GraphBundleLoad load = mgrl::loadGraphBundle(tmp.path / "nothing", "k1");
  REQUIRE(load.status == GraphBundleLoad::Missing);
}

TEST_CASE("a bundle made for another key is stale", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  mgrl::saveGraphBundle(tmp.path / "graph", tinyModel(), provenance("k1"));
  const GraphBundleLoad load = mgrl::loadGraphBundle(tmp.path / "graph", "k2");
  REQUIRE(load.status == GraphBundleLoad::Stale);
  REQUIRE_THAT(load.reason, Contains("manifest.json: expected cache key 'k2', found 'k1'"));
  REQUIRE(load.model.actionFrames.empty());
}

TEST_CASE("a bundle of another format version is stale", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  manifest["version"] = mgrl::kGraphFormatVersion + 1;
  writeBytes(bundle / "manifest.json", manifest.dump());
  const GraphBundleLoad load = mgrl::loadGraphBundle(bundle, "k1");
  REQUIRE(load.status == GraphBundleLoad::Stale);
  REQUIRE_THAT(load.reason, Contains(fmt::format("expected format 'mgrl.graph' version {}, found format 'mgrl.graph' "
                                                 "version '{}'",
                                                 mgrl::kGraphFormatVersion, mgrl::kGraphFormatVersion + 1)));
}

// The scalars were covered by no hash, so one flipped digit of
// frame_time was reused silently and changed every figure computed from the graph.
TEST_CASE("a bundle whose manifest has one changed digit is damaged", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  const std::string text = mgrl::readFile(bundle / "manifest.json");
  // The text after `"<member>": `, in the manifest as written.
  std::string member;
  SECTION("frame_time") { member = "\"frame_time\": "; }
  SECTION("centroid") { member = "\"centroid\": [\n"; }
  SECTION("max_hit_speed_mps") { member = "\"max_hit_speed_mps\": "; }
  SECTION("max_kick_speed_mps") { member = "\"max_kick_speed_mps\": "; }
  SECTION("frames_total") { member = "\"frames_total\": "; }
  SECTION("a provenance value") { member = "\"seed\": "; }
  CAPTURE(member);
  const std::size_t at = text.find(member);
  REQUIRE(at != std::string::npos);
  // The last digit of the (first) number: still a valid manifest, only a different value.
  std::size_t digit = text.find_first_of("0123456789", at + member.size());
  while (digit + 1 < text.size() && (std::isdigit(static_cast<unsigned char>(text[digit + 1])) || text[digit + 1] == '.'))
    ++digit;
  REQUIRE(std::isdigit(static_cast<unsigned char>(text[digit])));
  std::string changed = text;
  changed[digit] = changed[digit] == '7' ? '8' : '7';
  writeBytes(bundle / "manifest.json", changed);
  REQUIRE_NOTHROW(json::parse(changed));
  requireDamaged(bundle, "manifest.json: expected its members to hash to '");
  requireDamaged(bundle, "(the file was altered)");
}

// The same through the graph step every command uses: said once, rebuilt, saved again.
TEST_CASE("a cached graph whose frame time lost a digit is rebuilt with one message", "[graph_cache][data]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const mgrl::Scenario scenario = mgrl::parseScenario("name: mini\nmotion:\n  files: [cmu/bvh/13_17_boxing.bvh]\n"
                                                      "  fps: 30\ngraph:\n  threshold: 0.4\n",
                                                      fs::path(MGRL_SOURCE_DIR) / "scenarios" / "test.yaml",
                                                      mgrl::test::mocap());
  std::vector<std::string> log;
  mgrl::GraphOptions options;
  options.plugins = &mgrl::builtinPlugins();
  options.cacheDir = tmp.path;
  options.log = [&](const std::string& line) { log.push_back(line); };
  const mgrl::GraphResult first = mgrl::obtainGraph(scenario, options);
  REQUIRE_FALSE(first.fromCache);
  const fs::path manifestPath = first.bundle / "manifest.json";
  std::string text = mgrl::readFile(manifestPath);
  const std::size_t at = text.find("\"frame_time\": 0.0");
  REQUIRE(at != std::string::npos);
  text[at + 17] = text[at + 17] == '3' ? '4' : '3';  // one digit: 1/30 s would read as 1/23 s
  writeBytes(manifestPath, text);

  log.clear();
  const mgrl::GraphResult second = mgrl::obtainGraph(scenario, options);
  CHECK_FALSE(second.fromCache);
  CHECK(second.model.frameTime == first.model.frameTime);
  const auto damaged = std::count_if(log.begin(), log.end(), [&](const std::string& line) {
    return line.rfind("graph: cache is damaged, rebuilding (" + manifestPath.string() +
                          ": expected its members to hash to '",
                      0) == 0;
  });
  CAPTURE(log);
  CHECK(damaged == 1);
  CHECK(mgrl::obtainGraph(scenario, options).fromCache);
}

TEST_CASE("a graph manifest's hash covers every member but itself", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  REQUIRE(manifest["hash"].is_string());
  REQUIRE(manifest["hash"] == mgrl::manifestHash(manifest));
  json other = manifest;
  other["scalars"]["frame_time"] = manifest["scalars"]["frame_time"].get<double>() * (1 + 1e-15);
  REQUIRE(mgrl::manifestHash(other) != mgrl::manifestHash(manifest));
  // The text's layout does not matter, only the values.
  writeBytes(bundle / "manifest.json", manifest.dump());
  REQUIRE(mgrl::loadGraphBundle(bundle, "k1").status == GraphBundleLoad::Ok);
  SECTION("a manifest without its hash is damaged") {
    manifest.erase("hash");
    writeBytes(bundle / "manifest.json", manifest.dump());
    requireDamaged(bundle, "manifest.json: manifest: expected the key 'hash', found none");
  }
  SECTION("a hash of another type is damaged") {
    manifest["hash"] = 12;
    writeBytes(bundle / "manifest.json", manifest.dump());
    requireDamaged(bundle, "manifest.json: hash: expected a string, found '12'");
  }
}

TEST_CASE("a bundle with a flipped byte is damaged", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  std::string bytes = mgrl::readFile(bundle / "action_frames.npy");
  bytes[bytes.size() - 3] ^= 0x10;
  writeBytes(bundle / "action_frames.npy", bytes);
  requireDamaged(bundle, "action_frames.npy: expected hash '");
  requireDamaged(bundle, "(the file was altered)");
}

TEST_CASE("a bundle with a truncated file is damaged", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  const std::string bytes = mgrl::readFile(bundle / "frame_root.npy");
  writeBytes(bundle / "frame_root.npy", bytes.substr(0, bytes.size() - 8));
  requireDamaged(bundle, fmt::format("frame_root.npy: expected {} bytes as in manifest.json, found {}", bytes.size(),
                                     bytes.size() - 8));
}

TEST_CASE("a bundle with a deleted file is damaged", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  fs::remove(bundle / "hits_value.npy");
  requireDamaged(bundle, "hits_value.npy: expected the file listed in manifest.json, found none");
}

TEST_CASE("a bundle with a garbage manifest is damaged", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  writeBytes(bundle / "manifest.json", "{\"format\": \"mgrl.gr");
  requireDamaged(bundle, "manifest.json: expected JSON, found a syntax error");

  writeBytes(bundle / "manifest.json", "[1, 2]");
  requireDamaged(bundle, "manifest.json: manifest: expected a JSON object, found '[1,2]'");

  fs::remove(bundle / "manifest.json");
  requireDamaged(bundle, "manifest.json");
}

TEST_CASE("a bundle whose manifest lacks or mistypes a member is damaged", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"));
  const json good = json::parse(mgrl::readFile(bundle / "manifest.json"));
  json manifest = good;
  std::string reason;
  // Each edit is sealed with a fresh hash, as a careful hand edit would be, so the member
  // checks behind the hash are exercised too.
  SECTION("no scalars") {
    manifest.erase("scalars");
    reason = "manifest: expected the key 'scalars', found none";
  }
  SECTION("frames_total as a string") {
    manifest["scalars"]["frames_total"] = "20";
    reason = "scalars.frames_total: expected an integer in [0, 4294967295], found '\"20\"'";
  }
  SECTION("no provenance key") {
    manifest["provenance"].erase("key");
    reason = "provenance: expected the key 'key', found none";
  }
  SECTION("an array missing from the manifest") {
    manifest["arrays"].erase("state_frame");
    reason = "arrays: expected the key 'state_frame', found none";
  }
  SECTION("an unknown array") {
    manifest["arrays"]["extra"] = manifest["arrays"]["state_frame"];
    reason = "arrays: expected only the arrays of a state-action model, found 'extra'";
  }
  SECTION("a file name outside the bundle") {
    manifest["arrays"]["state_frame"]["file"] = "../state_frame.npy";
    reason = "arrays.state_frame.file: expected 'state_frame.npy', found '\"../state_frame.npy\"'";
  }
  SECTION("another dtype") {
    manifest["arrays"]["frame_root"]["dtype"] = "<f4";
    reason = "arrays.frame_root.dtype: expected '<f8'";
  }
  SECTION("a shape that disagrees with the file") {
    manifest["arrays"]["frame_root"]["shape"] = json::array({54});
    reason = "frame_root.npy: expected shape (54,) as in manifest.json, found (18, 3)";
  }
  SECTION("joint names that are not strings") {
    manifest["scalars"]["joint_names"] = json::array({"Hips", 3});
    reason = "scalars.joint_names: expected an array of at most 1000 joint names";
  }
  SECTION("a joint name with a control character") {
    manifest["scalars"]["joint_names"][1] = "Left\x1b[2JHand";
    reason = "scalars.joint_names: expected joint names of 1 to 200 printable characters";
  }
  SECTION("a joint name too many for the joint arrays") {
    manifest["scalars"]["joint_names"].push_back("RightHand");
    reason = "sourceJoint: expected 180 entries (3 per source frame and joint), found 120";
  }
  SECTION("a frame time of 0") {
    manifest["scalars"]["frame_time"] = 0.0;
    reason = "frameTime: expected a finite number of seconds above 0, found 0";
  }
  manifest["hash"] = mgrl::manifestHash(manifest);
  writeBytes(bundle / "manifest.json", manifest.dump());
  requireDamaged(bundle, reason);
}

TEST_CASE("a bundle whose arrays break the model is damaged even with correct hashes", "[graph_cache]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  StateActionModel model = tinyModel();
  mgrl::saveGraphBundle(bundle, model, provenance("k1"));
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  // Replaces one array with a well-formed file and updates the manifest to match it.
  auto rewrite = [&](const std::string& name, const std::string& bytes) {
    writeBytes(bundle / (name + ".npy"), bytes);
    manifest["arrays"][name]["bytes"] = bytes.size();
    manifest["arrays"][name]["hash"] = mgrl::hexDigest(mgrl::hashBytes(bytes));
    manifest["hash"] = mgrl::manifestHash(manifest);
    writeBytes(bundle / "manifest.json", manifest.dump());
  };

  SECTION("a frame index past framesTotal") {
    model.actionFrames[0] = 20;
    rewrite("action_frames", mgrl::npyEncode<std::uint32_t>(model.actionFrames, {model.actionFrames.size()}));
    requireDamaged(bundle, "actionFrames[0]: expected a frame below framesTotal 20, found 20");
  }
  SECTION("a hand that uint8 would wrap") {
    std::vector<std::uint32_t> index;
    for (const auto& hit : model.hits) index.insert(index.end(), {hit.action, hit.offset, hit.hand});
    index[2] = 257;
    rewrite("hits_index", mgrl::npyEncode<std::uint32_t>(index, {4, 3}));
    requireDamaged(bundle, "hits_index.npy: row 0: expected side 0 or 1 in column 2, found 257");
  }
  SECTION("a 1-D file where rows of 3 belong") {
    rewrite("frame_root", mgrl::npyEncode<double>(model.frameRoot, {model.frameRoot.size()}));
    manifest["arrays"]["frame_root"]["shape"] = json::array({model.frameRoot.size()});
    manifest["hash"] = mgrl::manifestHash(manifest);
    writeBytes(bundle / "manifest.json", manifest.dump());
    requireDamaged(bundle, "frame_root.npy: expected shape (N, 3), found (54,)");
  }
  SECTION("a file of another dtype") {
    const std::vector<float> frames(model.actionFrames.begin(), model.actionFrames.end());
    rewrite("action_frames", mgrl::npyEncode<float>(frames, {frames.size()}));
    requireDamaged(bundle, "action_frames.npy: expected descr '<u4', found '<f4'");
  }
}

// --- the capture's motions (version 4) --------------------------------------------------

namespace {

// tinyModel()'s two clips of 10 frames, cut from a real BVH (an end site, position
// channels on the root only) and given the model's frame time.
std::vector<mgrl::Clip> tinyClips() {
  const mgrl::Motion source = mgrl::loadMotion(mgrl::test::testData() / "boxer21.bvh").motion;
  std::vector<mgrl::Clip> clips;
  for (std::size_t first : {0, 40}) {
    std::vector<Eigen::Quaterniond> rotations;
    std::vector<Eigen::Vector3d> translations;
    for (std::size_t f = first; f < first + 10; ++f) {
      for (const auto& q : source.rotations(f)) rotations.push_back(q);
      for (const auto& t : source.translations(f)) translations.push_back(t);
    }
    clips.push_back(mgrl::Clip{fmt::format("clip{}.bvh", first), {},
                               mgrl::Motion(source.sharedSkeleton(), 1.0 / 30, rotations, translations), {}});
  }
  return clips;
}

GraphBundleLoad loadWithMotion(const fs::path& bundle) { return mgrl::loadGraphBundle(bundle, "k1", true); }

}  // namespace

TEST_CASE("a graph bundle keeps the capture's motions bit for bit, and reads them only when asked",
          "[graph_cache][motion]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const std::vector<mgrl::Clip> clips = tinyClips();
  mgrl::saveGraphBundle(tmp.path / "graph", tinyModel(), provenance("k1"), clips);

  const GraphBundleLoad load = loadWithMotion(tmp.path / "graph");
  CAPTURE(load.reason);
  REQUIRE(load.status == GraphBundleLoad::Ok);
  requireSameModel(load.model, tinyModel());
  REQUIRE(load.motions.size() == 2);
  for (std::size_t c = 0; c < 2; ++c) {
    CAPTURE(c);
    const mgrl::Motion& a = clips[c].motion;
    const mgrl::Motion& b = load.motions[c].second;
    CHECK(load.motions[c].first == clips[c].name);
    CHECK(b.frameTime() == a.frameTime());
    REQUIRE(b.frameCount() == a.frameCount());
    REQUIRE(b.skeleton().jointCount() == a.skeleton().jointCount());
    for (std::size_t j = 0; j < a.skeleton().jointCount(); ++j) {
      CHECK(b.skeleton().joint(j).name == a.skeleton().joint(j).name);
      CHECK(b.skeleton().joint(j).parent == a.skeleton().joint(j).parent);
      CHECK(b.skeleton().joint(j).offset == a.skeleton().joint(j).offset);
      CHECK(b.skeleton().joint(j).channels == a.skeleton().joint(j).channels);
      CHECK(b.skeleton().joint(j).endSite == a.skeleton().joint(j).endSite);
    }
    for (std::size_t f = 0; f < a.frameCount(); ++f) {
      for (std::size_t j = 0; j < a.skeleton().jointCount(); ++j)
        REQUIRE(b.rotation(f, j).coeffs() == a.rotation(f, j).coeffs());
      REQUIRE(b.translations(f).size() == 1);
      REQUIRE(b.translations(f)[0] == a.translations(f)[0]);
    }
  }

  // Not asked for: not read (eval and train need only the model).
  const GraphBundleLoad modelOnly = mgrl::loadGraphBundle(tmp.path / "graph", "k1");
  REQUIRE(modelOnly.status == GraphBundleLoad::Ok);
  CHECK(modelOnly.motions.empty());
  // Saved without: none, and the bundle is still good.
  mgrl::saveGraphBundle(tmp.path / "bare", tinyModel(), provenance("k1"));
  const GraphBundleLoad bare = loadWithMotion(tmp.path / "bare");
  REQUIRE(bare.status == GraphBundleLoad::Ok);
  CHECK(bare.motions.empty());
  CHECK(namesIn(tmp.path / "bare").size() + 2 == namesIn(tmp.path / "graph").size());
}

TEST_CASE("saveGraphBundle refuses clips that are not the model's and writes nothing", "[graph_cache][motion]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  std::vector<mgrl::Clip> clips = tinyClips();
  clips.pop_back();
  REQUIRE_THROWS_WITH(mgrl::saveGraphBundle(tmp.path / "graph", tinyModel(), provenance("k1"), clips),
                      Contains("graph: expected the 2 clips of 20 frames the model was built from, found 1 of 10"));
  CHECK_FALSE(fs::exists(tmp.path / "graph"));
}

TEST_CASE("a bundle whose kept motion is inconsistent is damaged, with the member or row named",
          "[graph_cache][motion]") {
  mgrl::test::TempDir tmp("graph-cache-test");
  const fs::path bundle = tmp.path / "graph";
  const std::vector<mgrl::Clip> clips = tinyClips();
  mgrl::saveGraphBundle(bundle, tinyModel(), provenance("k1"), clips);
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  json& clip0 = manifest["motion"]["clips"][0];
  std::string reason;
  // Each edit is sealed with a fresh hash (a careful hand edit), so the checks behind it run.
  auto rewrite = [&](const std::string& name, const std::string& bytes) {
    writeBytes(bundle / (name + ".npy"), bytes);
    manifest["arrays"][name]["bytes"] = bytes.size();
    manifest["arrays"][name]["hash"] = mgrl::hexDigest(mgrl::hashBytes(bytes));
  };
  std::vector<double> rotations;
  for (const mgrl::Clip& c : clips)
    for (std::size_t f = 0; f < 10; ++f)
      for (const auto& q : c.motion.rotations(f)) rotations.insert(rotations.end(), {q.x(), q.y(), q.z(), q.w()});
  const std::size_t rows = rotations.size() / 4;

  SECTION("frames that disagree with clip_offset") {
    clip0["frames"] = 11;
    reason = "motion.clips[0].frames: expected 10 as clip_offset.npy says, found '11'";
  }
  SECTION("another frame time") {
    clip0["frame_time"] = 0.04;
    reason = "motion.clips[0].frame_time: expected scalars.frame_time, found '0.04'";
  }
  SECTION("a clip missing") {
    manifest["motion"]["clips"].erase(1);
    reason = "motion.clips: expected 2 clips as clip_offset.npy says, found 1";
  }
  SECTION("an unknown channel") {
    clip0["joints"][0]["channels"][0] = "Wrotation";
    reason = "motion.clips[0].joints[0].channels: expected channel names such as 'Zrotation' or 'Xposition', "
             "found '\"Wrotation\"'";
  }
  SECTION("a joint listed before its parent") {
    clip0["joints"][1]["parent"] = 3;
    reason = "motion.clips[0].joints: skeleton: joint";
  }
  SECTION("a parent far out of range") {
    clip0["joints"][1]["parent"] = 1e9;
    reason = "motion.clips[0].joints[1].parent: expected an integer in [-1, 1000)";
  }
  SECTION("a non-finite offset") {
    clip0["joints"][2]["offset"] = json::array({0.0, "nan", 1.0});
    reason = "motion.clips[0].joints[2].offset: expected 3 finite numbers";
  }
  SECTION("no joints") {
    clip0["joints"] = json::array();
    reason = "motion.clips[0].joints: expected an array of 1 to 1000 joints, found 0";
  }
  SECTION("joints that are not an array") {
    clip0["joints"] = 1;
    reason = "motion.clips[0].joints: expected an array of 1 to 1000 joints, found '1'";
  }
  SECTION("clips that are not an array") {
    manifest["motion"]["clips"] = "all";
    reason = "motion.clips: expected an array of 1 to 100000 clips, found '\"all\"'";
  }
  SECTION("no clips") {
    manifest["motion"]["clips"] = json::array();
    reason = "motion.clips: expected an array of 1 to 100000 clips, found '[]'";
  }
  SECTION("a clip that is not an object") {
    manifest["motion"]["clips"][1] = 7;
    reason = "motion.clips[1]: expected an object, found '7'";
  }
  SECTION("an end site of two numbers") {
    clip0["joints"][2]["end_site"] = json::array({0.0, 1.0});
    reason = "motion.clips[0].joints[2].end_site: expected 3 finite numbers, found '[0.0,1.0]'";
  }
  SECTION("seven channels") {
    clip0["joints"][0]["channels"] =
        json::array({"Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation", "Zrotation"});
    reason = "motion.clips[0].joints[0].channels: expected an array of at most 6 channel names, found '[";
  }
  SECTION("an unknown key") {
    clip0["scale"] = 2;
    reason = "motion.clips[0]: expected only the keys name, frames, frame_time, joints, found '\"scale\"'";
  }
  SECTION("a rotation that is not a unit quaternion") {
    rotations[4 * 13 + 3] *= 2;
    rewrite("motion_rotations", mgrl::npyEncode<double>(rotations, {rows, 4}));
    reason = "motion_rotations.npy: row 13: expected a unit quaternion";
  }
  SECTION("a translation that is not finite") {
    std::vector<double> translations;
    for (const mgrl::Clip& c : clips)
      for (std::size_t f = 0; f < 10; ++f)
        for (const auto& t : c.motion.translations(f)) translations.insert(translations.end(), {t.x(), t.y(), t.z()});
    translations[3 * 12 + 1] = std::nan("");
    rewrite("motion_translations", mgrl::npyEncode<double>(translations, {translations.size() / 3, 3}));
    reason = "motion_translations.npy: row 12: expected finite numbers, found (";
  }
  SECTION("fewer rotation rows than the clips need") {
    rotations.resize(rotations.size() - 4);
    rewrite("motion_rotations", mgrl::npyEncode<double>(rotations, {rows - 1, 4}));
    manifest["arrays"]["motion_rotations"]["shape"] = json::array({rows - 1, 4});
    reason = fmt::format("motion_rotations.npy: expected shape ({}, 4) as motion.clips says, found ({}, 4)", rows,
                         rows - 1);
  }
  SECTION("more translation rows than the clips need") {
    std::vector<double> translations;
    for (const mgrl::Clip& c : clips)
      for (std::size_t f = 0; f < 10; ++f)
        for (const auto& t : c.motion.translations(f)) translations.insert(translations.end(), {t.x(), t.y(), t.z()});
    const std::size_t translationRows = translations.size() / 3;
    translations.insert(translations.end(), {0.0, 0.0, 0.0});
    rewrite("motion_translations", mgrl::npyEncode<double>(translations, {translationRows + 1, 3}));
    manifest["arrays"]["motion_translations"]["shape"] = json::array({translationRows + 1, 3});
    reason = fmt::format("motion_translations.npy: expected shape ({}, 3) as motion.clips says, found ({}, 3)",
                         translationRows, translationRows + 1);
  }
  SECTION("the rotations' array not listed") {
    manifest["arrays"].erase("motion_rotations");
    reason = "arrays: expected the key 'motion_rotations', found none";
  }
  manifest["hash"] = mgrl::manifestHash(manifest);
  writeBytes(bundle / "manifest.json", manifest.dump());
  const GraphBundleLoad load = loadWithMotion(bundle);
  CAPTURE(load.reason);
  REQUIRE(load.status == GraphBundleLoad::Damaged);
  REQUIRE_THAT(load.reason, Contains(reason));
  CHECK(load.motions.empty());
}

}  // namespace graph_cache_test
