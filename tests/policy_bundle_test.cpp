// Policy bundles and training checkpoints: Q tables and vertices round-trip exactly through
// savePolicyBundle/loadPolicyBundle and are plain NumPy arrays; every way a bundle can be
// missing, stale, altered or malformed is refused with one line naming the file; a failed
// save leaves nothing behind. DirectoryCheckpointer resumes only an intact checkpoint of
// the same run and reports, never throws, for anything else.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "mgrl/learning/checkpoint_store.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/core/npy.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace policy_bundle_test {

namespace fs = std::filesystem;
using Catch::Contains;
using mgrl::PolicyBehavior;
using mgrl::PolicyBundle;
using mgrl::QTable;
using mgrl::StateActionModel;
using nlohmann::json;

namespace {

// Only what a Q table's layout depends on: state 0 has actions 0 and 1, state 1 action 2
// (and, with `fourActions`, state 2 action 3).
StateActionModel tableModel(bool fourActions = false) {
  StateActionModel m;
  m.actionFrom = {0, 0, 1};
  m.actionTo = {1, 0, 0};
  m.stateActionBegin = {0, 2, 3};
  if (fourActions) {
    m.actionFrom.push_back(2);
    m.actionTo.push_back(0);
    m.stateActionBegin.push_back(4);
  }
  return m;
}

const std::string kGraphKey = "0123456789abcdef0123456789abcdef";
const std::string kOtherGraphKey = "fedcba9876543210fedcba9876543210";

// A table whose every value tells its action and vertex apart.
QTable filledTable(const StateActionModel& model, std::size_t vertexCount, float scale) {
  QTable q(model, vertexCount);
  for (std::size_t a = 0; a < q.actionCount(); ++a)
    for (std::size_t v = 0; v < vertexCount; ++v)
      q.at(a, v) = scale * (static_cast<float>(a) + 0.01f * static_cast<float>(v)) - 0.5f;
  return q;
}

PolicyBehavior behavior(const StateActionModel& model, std::size_t vertexCount, float scale) {
  PolicyBehavior b;
  b.key = fmt::format("behaviour-key-{}", scale);
  b.record = {{"learner", "q_learning"}, {"params", {{"alpha", 0.5}, {"gamma", 0.9}}}, {"curve", {1.5, 0.25}}};
  b.table = filledTable(model, vertexCount, scale);
  for (std::size_t v = 0; v < vertexCount; ++v)
    b.vertices.insert(b.vertices.end(), {0.1 * static_cast<double>(v), 1.0, -0.25 * static_cast<double>(v)});
  return b;
}

PolicyBundle sampleBundle(const StateActionModel& model) {
  PolicyBundle bundle;
  bundle.graphKey = kGraphKey;
  bundle.provenance = {{"scenario", "boxing"}, {"scenario_path", "/x/boxing.yaml"}, {"tool_version", "0.1"}};
  bundle.behaviors["hit"] = behavior(model, 5, 1.0f);
  bundle.behaviors["walk-2_b"] = behavior(model, 7, -2.0f);
  return bundle;
}

void writeBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  REQUIRE(out.good());
}

std::vector<std::string> namesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::map<std::string, std::string> filesIn(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir))
    files[entry.path().filename().string()] = mgrl::readFile(entry.path());
  return files;
}

// Writes an edited manifest sealed again (its "hash" recomputed, as a script that knows the
// format could), so that the checks behind the seal are the ones that catch the edit.
void writeResealed(const fs::path& bundle, json manifest) {
  if (manifest.contains("hash")) manifest["hash"] = mgrl::manifestHash(manifest);
  writeBytes(bundle / "manifest.json", manifest.dump());
}

// Replaces an array file with well-formed `bytes` and updates its manifest entry to match,
// so only the content checks after the hashes can catch what is wrong.
void rewriteArray(const fs::path& bundle, json& manifest, const std::string& behavior, const std::string& array,
                  const std::string& file, const std::string& bytes, const std::vector<std::size_t>& shape) {
  writeBytes(bundle / file, bytes);
  json& entry = manifest["behaviors"][behavior][array];
  entry["bytes"] = bytes.size();
  entry["hash"] = mgrl::hexDigest(mgrl::hashBytes(bytes));
  entry["shape"] = shape;
  writeResealed(bundle, manifest);
}

// Collects what a checkpointer logs.
struct Log {
  std::vector<std::string> lines;
  mgrl::WarningSink sink() {
    return [this](const std::string& line) { lines.push_back(line); };
  }
};

}  // namespace

// --- policy bundles ----------------------------------------------------------------------

TEST_CASE("a policy bundle round-trips tables, vertices, records and provenance", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const PolicyBundle saved = sampleBundle(model);
  mgrl::savePolicyBundle(tmp.path / "policy", saved);

  REQUIRE(namesIn(tmp.path) == std::vector<std::string>{"policy"});
  REQUIRE(namesIn(tmp.path / "policy") ==
          std::vector<std::string>{"hit.q.npy", "hit.vertices.npy", "manifest.json", "walk-2_b.q.npy",
                                   "walk-2_b.vertices.npy"});

  const PolicyBundle loaded = mgrl::loadPolicyBundle(tmp.path / "policy/", model, kGraphKey);
  REQUIRE(loaded.graphKey == kGraphKey);
  REQUIRE(loaded.provenance == saved.provenance);
  REQUIRE(loaded.behaviors.size() == 2);
  for (const auto& [name, original] : saved.behaviors) {
    CAPTURE(name);
    REQUIRE(loaded.behaviors.contains(name));
    const PolicyBehavior& b = loaded.behaviors.at(name);
    CHECK(b.key == original.key);
    CHECK(b.record == original.record);
    CHECK(b.table == original.table);
    CHECK(b.vertices == original.vertices);
  }

  const json manifest = json::parse(mgrl::readFile(tmp.path / "policy" / "manifest.json"));
  REQUIRE(manifest["format"] == "mgrl.policy");
  REQUIRE(manifest["version"] == mgrl::kPolicyFormatVersion);
  REQUIRE(manifest["behaviors"]["hit"]["table"]["file"] == "hit.q.npy");
  REQUIRE(manifest["behaviors"]["hit"]["table"]["dtype"] == "<f4");
  REQUIRE(manifest["behaviors"]["hit"]["vertices"]["dtype"] == "<f8");
}

TEST_CASE("a policy bundle's Q table is a NumPy float32 array of shape (actions, vertices)", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const PolicyBundle saved = sampleBundle(model);
  mgrl::savePolicyBundle(tmp.path / "policy", saved);

  std::vector<std::size_t> shape;
  const std::vector<float> q =
      mgrl::npyDecode<float>(mgrl::readFile(tmp.path / "policy" / "walk-2_b.q.npy"), "q", &shape);
  REQUIRE(shape == std::vector<std::size_t>{3, 7});
  const QTable& table = saved.behaviors.at("walk-2_b").table;
  for (std::size_t a = 0; a < 3; ++a)
    for (std::size_t v = 0; v < 7; ++v) REQUIRE(q[a * 7 + v] == table.at(a, v));

  const std::vector<double> vertices =
      mgrl::npyDecode<double>(mgrl::readFile(tmp.path / "policy" / "walk-2_b.vertices.npy"), "v", &shape);
  REQUIRE(shape == std::vector<std::size_t>{7, 3});
  REQUIRE(vertices == saved.behaviors.at("walk-2_b").vertices);
}

TEST_CASE("saving the same policy twice writes byte-identical files and replaces the old bundle", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  mgrl::savePolicyBundle(tmp.path / "a", sampleBundle(model));
  const auto first = filesIn(tmp.path / "a");
  mgrl::savePolicyBundle(tmp.path / "a", sampleBundle(model));
  mgrl::savePolicyBundle(tmp.path / "b", sampleBundle(model));
  REQUIRE(filesIn(tmp.path / "a") == first);
  REQUIRE(filesIn(tmp.path / "b") == first);

  PolicyBundle fewer = sampleBundle(model);
  fewer.behaviors.erase("walk-2_b");
  mgrl::savePolicyBundle(tmp.path / "a", fewer);
  REQUIRE(namesIn(tmp.path / "a") == std::vector<std::string>{"hit.q.npy", "hit.vertices.npy", "manifest.json"});
  REQUIRE(namesIn(tmp.path) == std::vector<std::string>{"a", "b"});
  REQUIRE(mgrl::loadPolicyBundle(tmp.path / "a", model, kGraphKey).behaviors.size() == 1);
}

TEST_CASE("a failed policy save leaves no temporary directory and deletes nothing", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  writeBytes(tmp.path / "file", "x");
  REQUIRE_THROWS_WITH(mgrl::savePolicyBundle(tmp.path / "file", sampleBundle(model)),
                      Contains("file: expected a policy bundle directory or nothing, found another kind of file"));

  fs::create_directories(tmp.path / "home");
  writeBytes(tmp.path / "home" / "notes.txt", "keep me");
  REQUIRE_THROWS_WITH(mgrl::savePolicyBundle(tmp.path / "home", sampleBundle(model)),
                      Contains("expected a policy bundle (with manifest.json) or an empty directory to replace"));
  REQUIRE(mgrl::readFile(tmp.path / "home" / "notes.txt") == "keep me");

  // A parent that is a file cannot be created.
  REQUIRE_THROWS_WITH(mgrl::savePolicyBundle(tmp.path / "file" / "policy", sampleBundle(model)),
                      Contains("policy: cannot create"));
  REQUIRE(namesIn(tmp.path) == std::vector<std::string>{"file", "home"});
}

TEST_CASE("savePolicyBundle refuses what it could not load back, writing nothing", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  PolicyBundle bundle = sampleBundle(model);
  std::string message;
  SECTION("a name that is not a file stem") {
    bundle.behaviors["../hit"] = behavior(model, 5, 1.0f);
    message = "policy: behaviors: expected names made of letters, digits, '_' and '-' (they name files), "
              "found '../hit'";
  }
  SECTION("a name with a dot") {
    bundle.behaviors["hit.q"] = behavior(model, 5, 1.0f);
    message = "found 'hit.q'";
  }
  SECTION("vertices that do not match the table") {
    bundle.behaviors["hit"].vertices.pop_back();
    message = "policy: behaviors.hit.vertices: expected 15 values (3 per vertex of the Q table), found 14";
  }
  SECTION("a NaN in a table") {
    bundle.behaviors["hit"].table.at(2, 3) = std::numeric_limits<float>::quiet_NaN();
    message = "policy: behaviors.hit.table: expected finite Q values, found nan at action 2, vertex 3";
  }
  SECTION("an infinite vertex") {
    bundle.behaviors["hit"].vertices[7] = INFINITY;
    message = "policy: behaviors.hit.vertices: expected finite positions, found inf at vertex 2";
  }
  SECTION("an empty table") {
    bundle.behaviors["hit"] = PolicyBehavior{};
    message = "policy: behaviors.hit.table: expected a Q table over at least one vertex, found none";
  }
  SECTION("provenance that is not an object") {
    bundle.provenance = json::array({1, 2});
    message = "policy: provenance: expected a JSON object, found '[1,2]'";
  }
  CAPTURE(message);
  REQUIRE_THROWS_AS(mgrl::savePolicyBundle(tmp.path / "policy", bundle), mgrl::Error);
  REQUIRE_THROWS_WITH(mgrl::savePolicyBundle(tmp.path / "policy", bundle), Contains(message));
  REQUIRE(namesIn(tmp.path).empty());
}

TEST_CASE("loadPolicyBundle refuses a missing, foreign or stale bundle with one line", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path bundle = tmp.path / "policy";
  mgrl::savePolicyBundle(bundle, sampleBundle(model));
  const json good = json::parse(mgrl::readFile(bundle / "manifest.json"));
  json manifest = good;
  fs::path dir = bundle;
  std::string message;
  SECTION("no directory") {
    dir = tmp.path / "nothing";
    message = "nothing: no policy bundle here: run `mgrl train` first (or pass --policy DIR)";
  }
  SECTION("a file instead of a directory") {
    writeBytes(tmp.path / "file", "x");
    dir = tmp.path / "file";
    message = "file: expected a policy bundle directory, found another kind of file";
  }
  SECTION("no manifest") {
    fs::remove(bundle / "manifest.json");
    message = "manifest.json: expected the manifest of a policy bundle, found no file";
  }
  SECTION("a garbage manifest") {
    writeBytes(bundle / "manifest.json", "{\"format\": \"mgrl.po");
    message = "manifest.json: expected JSON, found a syntax error";
  }
  SECTION("a manifest that is not an object") {
    writeBytes(bundle / "manifest.json", "[1, 2]");
    message = "manifest.json: manifest: expected a JSON object, found '[1,2]'";
  }
  SECTION("another format") {
    manifest["format"] = "mgrl.graph";
    message = "manifest.json: expected format 'mgrl.policy' version 2, found format 'mgrl.graph' version '2': "
              "retrain with `mgrl train`";
  }
  SECTION("another version") {
    manifest["version"] = 3;
    message = "expected format 'mgrl.policy' version 2, found format 'mgrl.policy' version '3'";
  }
  SECTION("an unknown top-level key") {
    manifest["extra"] = 1;
    message = "manifest.json: expected only the keys format, version, graph_key, provenance, behaviors, hash, found "
              "'extra'";
  }
  SECTION("a behaviour without a key") {
    manifest["behaviors"]["hit"].erase("key");
    message = "manifest.json: behaviors.hit: expected the key 'key', found none";
  }
  SECTION("a record that is not an object") {
    manifest["behaviors"]["hit"]["record"] = "fast";
    message = "manifest.json: behaviors.hit.record: expected an object, found '\"fast\"'";
  }
  if (manifest != good) writeResealed(bundle, manifest);
  CAPTURE(message);
  REQUIRE_THROWS_AS(mgrl::loadPolicyBundle(dir, model, kGraphKey), mgrl::Error);
  REQUIRE_THROWS_WITH(mgrl::loadPolicyBundle(dir, model, kGraphKey), Contains(message));
}

TEST_CASE("loadPolicyBundle refuses a bundle made for another graph, naming both keys", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  mgrl::savePolicyBundle(tmp.path / "policy", sampleBundle(model));
  try {
    mgrl::loadPolicyBundle(tmp.path / "policy", model, kOtherGraphKey);
    FAIL("expected mgrl::Error");
  } catch (const mgrl::Error& e) {
    const std::string message = e.what();
    CAPTURE(message);
    CHECK_THAT(message, Contains("policy/manifest.json: "));
    CHECK_THAT(message, Contains("made for another graph"));
    CHECK_THAT(message, Contains("expected graph key 'fedcba9876543210', found '0123456789abcdef'"));
    CHECK_THAT(message, !Contains(kGraphKey) && !Contains(kOtherGraphKey));
    CHECK_THAT(message, Contains("retrain with `mgrl train`"));
    CHECK(message.find('\n') == std::string::npos);
  }
}

// Audit finding: the manifest carried no hash of its own, so a graph key edited to match
// another graph, or an edited behaviour key or record, loaded without complaint.
TEST_CASE("loadPolicyBundle refuses a manifest edited by hand (its graph key or a behaviour's key or record)",
          "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path bundle = tmp.path / "policy";
  mgrl::savePolicyBundle(bundle, sampleBundle(model));
  REQUIRE_NOTHROW(mgrl::loadPolicyBundle(bundle, model, kGraphKey));  // untouched: it loads

  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  CHECK(manifest.value("hash", std::string()) == mgrl::manifestHash(manifest));
  std::string loadKey = kGraphKey;
  SECTION("the graph key, edited to pass for another graph's") {
    manifest["graph_key"] = kOtherGraphKey;
    loadKey = kOtherGraphKey;
  }
  SECTION("a behaviour's key") { manifest["behaviors"]["hit"]["key"] = "behaviour-key-edited"; }
  SECTION("a behaviour's record") { manifest["behaviors"]["walk-2_b"]["record"]["learner"] = "value_iteration"; }
  SECTION("a number in a record") { manifest["behaviors"]["hit"]["record"]["params"]["gamma"] = 0.95; }
  SECTION("the provenance") { manifest["provenance"]["scenario"] = "dodge"; }
  writeBytes(bundle / "manifest.json", manifest.dump(2));
  try {
    mgrl::loadPolicyBundle(bundle, model, loadKey);
    FAIL("expected mgrl::Error");
  } catch (const mgrl::Error& e) {
    const std::string message = e.what();
    CAPTURE(message);
    CHECK_THAT(message, Contains("policy/manifest.json: expected its members to hash to '" +
                                 manifest.value("hash", std::string()) + "' as its \"hash\" says, found '" +
                                 mgrl::manifestHash(manifest) + "'"));
    CHECK_THAT(message, Contains("was edited after it was written; retrain with `mgrl train`"));
    CHECK(message.find('\n') == std::string::npos);
  }
}

TEST_CASE("loadPolicyBundle refuses an unsealed manifest (its hash removed or a version 1 bundle)", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path bundle = tmp.path / "policy";
  mgrl::savePolicyBundle(bundle, sampleBundle(model));
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  manifest.erase("hash");
  std::string message;
  SECTION("the hash removed") {
    message = "policy/manifest.json: expected a \"hash\" member sealing the manifest, found none (removed by hand?): "
              "retrain with `mgrl train`";
  }
  SECTION("a bundle written before the seal") {
    manifest["version"] = 1;
    message = "policy/manifest.json: expected format 'mgrl.policy' version 2, found format 'mgrl.policy' version "
              "'1' (written before policy manifests were sealed by a hash, so an edit to its graph key or records "
              "could not be noticed): retrain with `mgrl train`";
  }
  SECTION("a hash that is not a string") {
    manifest["hash"] = 7;
    message = "policy/manifest.json: hash: expected a string of 16 hex digits, found '7': retrain with `mgrl train`";
  }
  writeBytes(bundle / "manifest.json", manifest.dump(2));
  CAPTURE(message);
  REQUIRE_THROWS_WITH(mgrl::loadPolicyBundle(bundle, model, kGraphKey), Contains(message));
}

TEST_CASE("loadPolicyBundle refuses behaviour names that are not file stems", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path bundle = tmp.path / "policy";
  mgrl::savePolicyBundle(bundle, sampleBundle(model));
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  std::string name;
  SECTION("a parent directory") { name = "../hit"; }
  SECTION("a dot") { name = "hit.q"; }
  SECTION("empty") { name = ""; }
  CAPTURE(name);
  manifest["behaviors"][name] = manifest["behaviors"]["hit"];
  writeResealed(bundle, manifest);
  REQUIRE_THROWS_WITH(mgrl::loadPolicyBundle(bundle, model, kGraphKey),
                      Contains(fmt::format("manifest.json: behaviors: expected names made of letters, digits, '_' "
                                           "and '-' (they name files), found '{}'",
                                           name)));
}

TEST_CASE("loadPolicyBundle refuses altered, truncated or missing files", "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path bundle = tmp.path / "policy";
  mgrl::savePolicyBundle(bundle, sampleBundle(model));
  const std::string bytes = mgrl::readFile(bundle / "hit.q.npy");
  std::string message;
  SECTION("a flipped byte") {
    std::string flipped = bytes;
    flipped[flipped.size() - 5] ^= 0x20;
    writeBytes(bundle / "hit.q.npy", flipped);
    message = "hit.q.npy: expected hash '";
  }
  SECTION("a truncated file") {
    writeBytes(bundle / "hit.q.npy", bytes.substr(0, bytes.size() - 4));
    message = fmt::format("hit.q.npy: expected {} bytes as in manifest.json, found {}", bytes.size(),
                          bytes.size() - 4);
  }
  SECTION("a deleted file") {
    fs::remove(bundle / "walk-2_b.vertices.npy");
    message = "walk-2_b.vertices.npy: expected the file listed in manifest.json, found none";
  }
  SECTION("a file name pointing outside the bundle") {
    json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
    manifest["behaviors"]["hit"]["table"]["file"] = "../hit.q.npy";
    writeResealed(bundle, manifest);
    message = "manifest.json: behaviors.hit.table.file: expected 'hit.q.npy', found '\"../hit.q.npy\"'";
  }
  CAPTURE(message);
  REQUIRE_THROWS_WITH(mgrl::loadPolicyBundle(bundle, model, kGraphKey), Contains(message));
}

TEST_CASE("loadPolicyBundle refuses tables and vertices of the wrong shape or with non-finite values",
          "[policy_bundle]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path bundle = tmp.path / "policy";
  const PolicyBundle saved = sampleBundle(model);
  mgrl::savePolicyBundle(bundle, saved);
  json manifest = json::parse(mgrl::readFile(bundle / "manifest.json"));
  StateActionModel loadModel = model;
  std::string message;
  SECTION("a graph with another number of actions") {
    loadModel = tableModel(true);
    message = "hit.q.npy: expected shape (4, V) (a row per action of the graph, V >= 1 vertices), found (3, 5)";
  }
  SECTION("a 1-D table") {
    const std::vector<float> q = saved.behaviors.at("hit").table.actionMajor();
    rewriteArray(bundle, manifest, "hit", "table", "hit.q.npy", mgrl::npyEncode<float>(q, {15}), {15});
    message = "hit.q.npy: expected shape (3, V) (a row per action of the graph, V >= 1 vertices), found (15,)";
  }
  SECTION("vertices for another table") {
    std::vector<double> vertices = saved.behaviors.at("hit").vertices;
    vertices.resize(12);
    rewriteArray(bundle, manifest, "hit", "vertices", "hit.vertices.npy", mgrl::npyEncode<double>(vertices, {4, 3}),
                 {4, 3});
    message = "hit.vertices.npy: expected shape (5, 3) (a row per vertex of hit.q.npy), found (4, 3)";
  }
  SECTION("a NaN in a table") {
    std::vector<float> q = saved.behaviors.at("hit").table.actionMajor();
    q[1 * 5 + 4] = std::numeric_limits<float>::quiet_NaN();
    rewriteArray(bundle, manifest, "hit", "table", "hit.q.npy", mgrl::npyEncode<float>(q, {3, 5}), {3, 5});
    message = "hit.q.npy: expected finite Q values, found nan at action 1, vertex 4";
  }
  SECTION("an infinite vertex") {
    std::vector<double> vertices = saved.behaviors.at("hit").vertices;
    vertices[4] = -INFINITY;
    rewriteArray(bundle, manifest, "hit", "vertices", "hit.vertices.npy", mgrl::npyEncode<double>(vertices, {5, 3}),
                 {5, 3});
    message = "hit.vertices.npy: expected finite positions, found -inf at vertex 1";
  }
  SECTION("a table of another dtype") {
    const std::vector<float> q = saved.behaviors.at("hit").table.actionMajor();
    const std::vector<double> wide(q.begin(), q.end());
    rewriteArray(bundle, manifest, "hit", "table", "hit.q.npy", mgrl::npyEncode<double>(wide, {3, 5}), {3, 5});
    message = "hit.q.npy: expected descr '<f4', found '<f8'";
  }
  CAPTURE(message);
  REQUIRE_THROWS_WITH(mgrl::loadPolicyBundle(bundle, loadModel, kGraphKey), Contains(message));
}

// --- checkpoints -------------------------------------------------------------------------

TEST_CASE("a directory checkpoint round-trips the learner's state and table", "[policy_bundle][checkpoint]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  Log log;
  mgrl::DirectoryCheckpointer checkpointer(tmp.path / "run" / "checkpoint", "run-key", model, 6, log.sink());

  QTable table(model, 6);
  REQUIRE_FALSE(checkpointer.load(table).has_value());
  REQUIRE(log.lines.empty());
  REQUIRE(table == QTable(model, 6));

  const json state = {{"episode", 12}, {"rng", "0123"}, {"alpha", 0.25}};
  checkpointer.save(state, filledTable(model, 6, 1.0f));
  const json later = {{"episode", 40}};
  checkpointer.save(later, filledTable(model, 6, 3.0f));  // replaces the first
  REQUIRE(namesIn(tmp.path / "run") == std::vector<std::string>{"checkpoint"});
  REQUIRE(namesIn(tmp.path / "run" / "checkpoint") == std::vector<std::string>{"state.json", "table.npy"});

  mgrl::DirectoryCheckpointer resumed(tmp.path / "run" / "checkpoint", "run-key", model, 6, log.sink());
  const std::optional<json> loaded = resumed.load(table);
  REQUIRE(loaded.has_value());
  REQUIRE(*loaded == later);
  REQUIRE(table == filledTable(model, 6, 3.0f));
  REQUIRE(log.lines.empty());

  resumed.remove();
  REQUIRE(namesIn(tmp.path / "run").empty());
  REQUIRE_FALSE(resumed.load(table).has_value());
  REQUIRE(log.lines.empty());
}

TEST_CASE("a damaged or foreign checkpoint is reported and ignored", "[policy_bundle][checkpoint]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path dir = tmp.path / "checkpoint";
  Log log;
  mgrl::DirectoryCheckpointer(dir, "run-key", model, 6, log.sink()).save({{"episode", 3}}, filledTable(model, 6, 1.0f));

  std::string key = "run-key";
  std::size_t vertexCount = 6;
  std::string message;
  bool replaceable = true;
  SECTION("a flipped byte in the table") {
    std::string bytes = mgrl::readFile(dir / "table.npy");
    bytes[bytes.size() - 2] ^= 0x01;
    writeBytes(dir / "table.npy", bytes);
    message = (dir / "table.npy").string() + ": expected hash '";
  }
  SECTION("a truncated table") {
    const std::string bytes = mgrl::readFile(dir / "table.npy");
    writeBytes(dir / "table.npy", bytes.substr(0, 100));
    message = (dir / "table.npy").string() + fmt::format(": expected {} bytes as in state.json, found 100", bytes.size());
  }
  SECTION("another run's key") {
    key = "other-key";
    message = (dir / "state.json").string() +
              ": expected key 'other-key', found 'run-key' (a checkpoint of other inputs or settings)";
  }
  SECTION("another grid") {
    vertexCount = 5;
    message = (dir / "table.npy").string() + ": expected shape (3, 5) (actions, vertices), found (3, 6)";
  }
  SECTION("garbage state") {
    writeBytes(dir / "state.json", "{\"format\": ");
    message = (dir / "state.json").string() + ": expected JSON, found a syntax error";
  }
  SECTION("no state file") {
    fs::remove(dir / "state.json");
    message = (dir / "state.json").string() + ": expected the state of a checkpoint, found no file";
    replaceable = false;  // a directory without state.json may not be ours
  }
  SECTION("another version") {
    json state = json::parse(mgrl::readFile(dir / "state.json"));
    state["version"] = 7;
    writeBytes(dir / "state.json", state.dump());
    message = fmt::format("expected format 'mgrl.checkpoint' version {}, found format 'mgrl.checkpoint' version '7'",
                          mgrl::kCheckpointFormatVersion);
  }
  // The learner's state was covered by no hash.
  SECTION("a changed digit in the learner's state") {
    std::string text = mgrl::readFile(dir / "state.json");
    const std::size_t at = text.find("\"episode\": 3");
    REQUIRE(at != std::string::npos);
    text[at + 11] = '4';
    writeBytes(dir / "state.json", text);
    message = (dir / "state.json").string() + ": expected its members to hash to '";
  }
  SECTION("a changed table entry in state.json") {
    json state = json::parse(mgrl::readFile(dir / "state.json"));
    state["table"]["shape"] = {6, 3};
    writeBytes(dir / "state.json", state.dump(2));
    message = (dir / "state.json").string() + ": expected its members to hash to '";
  }
  SECTION("no hash") {
    json state = json::parse(mgrl::readFile(dir / "state.json"));
    state.erase("hash");
    writeBytes(dir / "state.json", state.dump(2));
    message = (dir / "state.json").string() + ": manifest: expected the key 'hash', found none";
  }
  CAPTURE(message);
  mgrl::DirectoryCheckpointer checkpointer(dir, key, model, vertexCount, log.sink());
  QTable table(model, vertexCount);
  REQUIRE_NOTHROW(checkpointer.load(table));
  REQUIRE_FALSE(checkpointer.load(table).has_value());
  REQUIRE(table == QTable(model, vertexCount));  // untouched
  REQUIRE(log.lines.size() == 2);
  REQUIRE_THAT(log.lines[0], Contains(message));
  REQUIRE_THAT(log.lines[0], Contains("ignoring the checkpoint"));
  REQUIRE(log.lines[0].rfind(dir.string(), 0) == 0);  // starts with the path
  REQUIRE(log.lines[0].find('\n') == std::string::npos);

  // A new save replaces a checkpoint, however damaged.
  if (replaceable) {
    checkpointer.save({{"episode", 4}}, filledTable(model, vertexCount, 2.0f));
    REQUIRE(checkpointer.load(table) == json{{"episode", 4}});
    REQUIRE(table == filledTable(model, vertexCount, 2.0f));
  } else {
    REQUIRE_THROWS_WITH(checkpointer.save({{"episode", 4}}, table), Contains("not deleting it"));
  }
}

TEST_CASE("a checkpoint's state.json is sealed by a hash of all its other members", "[policy_bundle][checkpoint]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  Log log;
  mgrl::DirectoryCheckpointer(tmp.path / "checkpoint", "run-key", model, 6, log.sink())
      .save({{"episode", 3}}, filledTable(model, 6, 1.0f));
  const json state = json::parse(mgrl::readFile(tmp.path / "checkpoint" / "state.json"));
  REQUIRE(state["version"] == mgrl::kCheckpointFormatVersion);
  REQUIRE(state["hash"] == mgrl::manifestHash(state));
}

TEST_CASE("a checkpoint whose state the learner rejects is reported and ignored, its table unused",
          "[policy_bundle][checkpoint]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  const fs::path dir = tmp.path / "checkpoint";
  Log log;
  mgrl::DirectoryCheckpointer checkpointer(dir, "run-key", model, 6, log.sink());
  checkpointer.save({{"episode", 3}}, filledTable(model, 6, 1.0f));

  // The learner's check reads through the reader, which names the file.
  std::optional<std::uint64_t> episode;
  const mgrl::StateCheck check = [&](const json& state, const mgrl::ManifestReader& reader) {
    episode = reader.unsignedInteger(state, "state", "episode", 2);
  };
  QTable table(model, 6);
  REQUIRE_NOTHROW(checkpointer.loadChecked(table, check));
  REQUIRE_FALSE(checkpointer.loadChecked(table, check).has_value());
  REQUIRE(table == QTable(model, 6));  // untouched
  REQUIRE(log.lines.size() == 2);
  REQUIRE(log.lines[0] == (dir / "state.json").string() +
                              ": state.episode: expected an integer in [0, 2], found '3'; ignoring the checkpoint");

  // A state it accepts is returned, with the table.
  log.lines.clear();
  const mgrl::StateCheck lenient = [&](const json& state, const mgrl::ManifestReader& reader) {
    episode = reader.unsignedInteger(state, "state", "episode", 10);
  };
  REQUIRE(checkpointer.loadChecked(table, lenient) == json{{"episode", 3}});
  REQUIRE(episode == 3u);
  REQUIRE(table == filledTable(model, 6, 1.0f));
  REQUIRE(log.lines.empty());
}

TEST_CASE("a checkpointer leaves a directory that is not a checkpoint alone", "[policy_bundle][checkpoint]") {
  mgrl::test::TempDir tmp("policy-bundle-test");
  const StateActionModel model = tableModel();
  fs::create_directories(tmp.path / "home");
  writeBytes(tmp.path / "home" / "notes.txt", "keep me");
  Log log;
  mgrl::DirectoryCheckpointer checkpointer(tmp.path / "home", "run-key", model, 6, log.sink());
  QTable table(model, 6);
  REQUIRE_FALSE(checkpointer.load(table).has_value());
  REQUIRE(log.lines.size() == 1);
  REQUIRE_THROWS_WITH(checkpointer.save({}, table), Contains("not deleting it"));
  checkpointer.remove();
  REQUIRE(mgrl::readFile(tmp.path / "home" / "notes.txt") == "keep me");
  REQUIRE(namesIn(tmp.path) == std::vector<std::string>{"home"});

  REQUIRE_THROWS_WITH(checkpointer.save({}, QTable(model, 5)),
                      Contains("expected a Q table of 3 actions x 6 vertices, found 3 x 5"));
}

}  // namespace policy_bundle_test
