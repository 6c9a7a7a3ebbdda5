// `mgrl simulate` through the real binary (DESIGN.md sec. 5; app/simulate_command.cpp): the
// --json report and the text summary, the hit events as JSON lines, one BVH per avatar,
// determinism for a seed, refusals (exit 1, one line on stderr, nothing on stdout, no
// output left behind, no simulation started) and the trained policy against random
// actions. Each test trains the boxing scenario with small budgets (a second or two) in a
// cache folder of its own.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <chrono>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/motion/gltf.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_simulate_test {

namespace fs = std::filesystem;
using Catch::Contains;
using Catch::StartsWith;
using nlohmann::json;

namespace {

const std::string kBoxing = std::string(MGRL_SOURCE_DIR) + "/scenarios/boxing.yaml";
// Budgets that train boxing in about a second (the file asks for 5 M and 20 M updates).
// The learner budget is part of a behaviour's key, so simulate gets the same flags.
const std::string kFast = "--set behaviors.approach.learner.budget=200000 --set behaviors.hit.learner.budget=400000";
// What simulate calls the scratch folders it makes beside its outputs.
const std::string kScratchPrefix = ".mgrl-simulate";

using mgrl::test::lines;
using mgrl::test::readText;
using mgrl::test::Run;
using mgrl::test::shellWord;

// A fresh folder per test (cache, bundles, outputs, captured streams), removed at the end
// even when the test fails.
class Sandbox : public mgrl::test::CliSandbox {
 public:
  explicit Sandbox(const std::string& tag) : CliSandbox("mgrl_cli_simulate_" + tag) {}

  // Runs mgrl with `arguments` (shell words); the captured streams live outside dir() so
  // that listing dir() shows only what mgrl made.
  Run run(const std::string& arguments) { return mgrl::test::runMgrl(arguments, streams_); }

  Run train(const std::string& arguments = "") {
    return run("train " + shellWord(kBoxing) + " --json" + where() + " " + kFast + " " + arguments);
  }
  // The default bundle of the cache, trained with kFast.
  void trainPolicy() {
    const Run trained = train();
    INFO("stderr: " << trained.err);
    REQUIRE(trained.status == 0);
  }
  Run simulate(const std::string& arguments) {
    return run("simulate " + shellWord(kBoxing) + where() + " " + kFast + " " + arguments);
  }

 private:
  mgrl::test::TempDir streamsDir_{"cli_simulate_streams"};
  fs::path streams_ = streamsDir_.path;
};

// Every file or folder under `dir` whose name starts with the scratch prefix, or that is
// a bundle's temporary or replaced copy (`<folder>.tmp-PID-N`, `<folder>.old-PID-N`).
std::vector<std::string> scratchLeft(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& item : fs::recursive_directory_iterator(dir)) {
    const std::string name = item.path().filename().string();
    if (name.rfind(kScratchPrefix, 0) == 0 || name.find(".tmp-") != std::string::npos ||
        name.find(".old-") != std::string::npos)
      found.push_back(item.path().string());
  }
  return found;
}

// Names of the entries of `dir` (hidden ones too), sorted.
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& item : fs::directory_iterator(dir)) names.push_back(item.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The events file, one JSON object per line.
std::vector<json> readEvents(const fs::path& file) {
  std::vector<json> events;
  for (const std::string& line : lines(readText(file))) {
    INFO("line: " << line);
    json e;
    REQUIRE_NOTHROW(e = json::parse(line));
    REQUIRE(e.is_object());
    events.push_back(e);
  }
  return events;
}

// The refusal contract for mistakes found before any simulation: exit 1, nothing on
// stdout, and one line on stderr, "mgrl: " + what starts it, containing `detail`.
void requireRefusal(const Run& r, const std::string& start, const std::string& detail) {
  INFO("stderr: " << r.err);
  CHECK(r.status == 1);
  CHECK(r.out.empty());
  const std::vector<std::string> errLines = lines(r.err);
  REQUIRE(errLines.size() == 1);
  CHECK_THAT(errLines.front(), StartsWith("mgrl: " + start) && Contains(detail));
}

void requireAbsent(const fs::path& p) {
  INFO(p);
  CHECK_FALSE(fs::exists(fs::symlink_status(p)));
}

// The keys every event line has, with their types.
void checkEventShape(const json& e) {
  INFO(e.dump());
  for (const char* key : {"time", "attacker", "target", "hand", "speed", "part", "blocked", "point"})
    CHECK(e.contains(key));
  CHECK(e["blocked"].is_boolean());
  CHECK(e["time"].is_number());
  CHECK(e["attacker"].is_number_integer());
  CHECK(e["target"].is_number_integer());
  CHECK((e["hand"] == "left" || e["hand"] == "right"));
  CHECK(e["speed"].is_number());
  CHECK(e["speed"].get<double>() > 0);
  CHECK(e["part"].is_string());
  REQUIRE(e["point"].is_array());
  CHECK(e["point"].size() == 3);
}

}  // namespace

TEST_CASE("mgrl simulate --json prints one report object, without it, a text summary", "[cli][data][simulate-cli]") {
  Sandbox box("contract");
  box.trainPolicy();

  const Run run = box.simulate("--json --avatars 4 --seconds 20.4 --seed 3");
  const json r = run.report();
  // stderr may carry log lines, all of them mgrl's.
  for (const std::string& line : lines(run.err)) CHECK_THAT(line, StartsWith("mgrl: "));

  for (const char* key : {"avatars", "frames", "avatar_frames_per_second", "hits", "hits_per_avatar_minute",
                          "hits_by_avatar", "hits_by_part", "seconds", "fps", "controller", "mode", "seed", "policy"})
    CHECK(r.contains(key));
  CHECK(r["avatars"] == 4);
  CHECK(r["controller"] == "policy");
  CHECK(r["mode"] == "sparring");
  CHECK(r["seed"] == 3);
  CHECK_THAT(r["policy"].get<std::string>(), StartsWith(box.cache().string()));
  CHECK_FALSE(r.contains("bvh_files"));
  CHECK_FALSE(r.contains("events_file"));

  const double fps = r["fps"].get<double>();
  CHECK(fps == Approx(30));  // the scenario's motion.fps
  const auto frames = r["frames"].get<long long>();
  CHECK(frames == std::llround(20.4 * fps));
  CHECK(r["seconds"].get<double>() == Approx(static_cast<double>(frames) / fps));
  CHECK(r["avatar_frames_per_second"].get<double>() > 0);

  const auto hits = r["hits"].get<long long>();
  CHECK(hits >= 0);
  REQUIRE(r["hits_by_avatar"].is_array());
  CHECK(r["hits_by_avatar"].size() == 4);
  long long byAvatar = 0;
  for (const json& n : r["hits_by_avatar"]) byAvatar += n.get<long long>();
  CHECK(byAvatar == hits);
  long long byPart = 0;
  for (const char* part : {"head", "chest", "spine", "target"}) byPart += r["hits_by_part"][part].get<long long>();
  CHECK(byPart == hits);
  CHECK(r["hits_by_part"]["target"] == 0);  // an even number of avatars spar in pairs
  CHECK(r["hits_per_avatar_minute"].get<double>() ==
        Approx(static_cast<double>(hits) / 4.0 / (static_cast<double>(frames) / fps / 60.0)));

  // The same run as text: a summary on stdout, with the same (deterministic) numbers.
  const Run text = box.simulate("--avatars 4 --seconds 20.4 --seed 3");
  INFO("stderr: " << text.err);
  REQUIRE(text.status == 0);
  CHECK_THROWS(json::parse(text.out));
  const std::vector<std::string> summary = lines(text.out);
  REQUIRE(summary.size() == 2);
  CHECK_THAT(summary[0], StartsWith("simulate (policy controller, sparring): 4 avatars x " + std::to_string(frames) +
                                    " frames (20.4 s)"));
  CHECK_THAT(summary[1], StartsWith("hits: " + std::to_string(hits) + " ("));
  for (const std::string& line : lines(text.err)) CHECK_THAT(line, StartsWith("mgrl: "));
  CHECK(scratchLeft(box.dir()).empty());
}

TEST_CASE("mgrl simulate --events-out writes one JSON line per hit", "[cli][data][simulate-cli]") {
  Sandbox box("events");
  box.trainPolicy();

  {  // sparring: every punch lands on the partner or is blocked by a forearm of his
    const fs::path file = box.path("hits.jsonl");
    const json r = box.simulate("--json --avatars 2 --seconds 60 --seed 2 --events-out " + shellWord(file)).report();
    CHECK(r["events_file"] == file.string());
    const auto hits = r["hits"].get<std::size_t>();
    const auto blocked = r["blocked"].get<std::size_t>();
    REQUIRE(hits > 0);
    REQUIRE(blocked > 0);  // the boxers' guards meet punches
    const std::vector<json> events = readEvents(file);
    REQUIRE(events.size() == hits + blocked);
    std::vector<long long> blockedBy(2, 0);

    const double seconds = r["seconds"].get<double>();
    double previous = 0;
    std::vector<long long> byAttacker(2, 0);
    std::map<std::string, long long> byPart;
    for (const json& e : events) {
      checkEventShape(e);
      INFO(e.dump());
      const double time = e["time"].get<double>();
      CHECK(time > 0);
      CHECK(time <= seconds + 1e-9);
      CHECK(time >= previous);  // in the order they happened
      previous = time;
      const auto attacker = e["attacker"].get<long long>();
      REQUIRE(attacker >= 0);
      REQUIRE(attacker < 2);
      CHECK(e["target"].get<long long>() == 1 - attacker);  // the pair's other boxer, never -1 here
      const std::string part = e["part"].get<std::string>();
      if (e["blocked"].get<bool>()) {
        CHECK((part == "left_arm" || part == "right_arm"));
        ++blockedBy[static_cast<std::size_t>(attacker)];
        continue;
      }
      CHECK((part == "head" || part == "chest" || part == "spine"));
      ++byAttacker[static_cast<std::size_t>(attacker)];
      ++byPart[part];
    }
    CHECK(json(byAttacker) == r["hits_by_avatar"]);
    CHECK(json(blockedBy) == r["blocked_by_avatar"]);
    for (const char* part : {"head", "chest", "spine"}) CHECK(byPart[part] == r["hits_by_part"][part].get<long long>());
  }
  {  // targets mode: every punch lands on the boxer's own target
    const fs::path file = box.path("targets.jsonl");
    const json r =
        box.simulate("--json --avatars 2 --seconds 60 --seed 2 --set world.mode=targets --events-out " + shellWord(file))
            .report();
    CHECK(r["mode"] == "targets");
    const auto hits = r["hits"].get<std::size_t>();
    REQUIRE(hits > 0);
    CHECK(r["hits_by_part"]["target"] == hits);
    CHECK(r["blocked"] == 0);  // a target has no guard
    const std::vector<json> events = readEvents(file);
    REQUIRE(events.size() == hits);
    double previous = 0;
    for (const json& e : events) {
      checkEventShape(e);
      INFO(e.dump());
      CHECK(e["target"] == -1);
      CHECK(e["part"] == "target");
      const auto attacker = e["attacker"].get<long long>();
      CHECK(attacker >= 0);
      CHECK(attacker < 2);
      const double time = e["time"].get<double>();
      CHECK(time > 0);
      CHECK(time <= r["seconds"].get<double>() + 1e-9);
      CHECK(time >= previous);
      previous = time;
    }
  }
  // Only the events files are left beside the cache: no scratch folder.
  CHECK(scratchLeft(box.dir()).empty());
  CHECK(entries(box.dir()) == std::vector<std::string>{"cache", "hits.jsonl", "targets.jsonl"});
}

TEST_CASE("mgrl simulate --bvh-out writes one readable BVH per avatar", "[cli][data][simulate-cli]") {
  Sandbox box("bvh");
  box.trainPolicy();
  const fs::path dir = box.path("out") / "bvh";  // made, parents and all
  const json r = box.simulate("--json --avatars 3 --seconds 10 --seed 4 --bvh-out " + shellWord(dir)).report();
  {
    // A killed run's scratch folder (its process gone) goes with the
    // next run into the same folder.
    const pid_t child = ::fork();
    if (child == 0) ::_exit(0);
    int status = 0;
    ::waitpid(child, &status, 0);
    const fs::path stale = dir / (".mgrl-simulate-" + std::to_string(child));
    fs::create_directories(stale);
    std::ofstream(stale / "avatar_000.bvh") << "half";
    REQUIRE(box.simulate("--json --avatars 3 --seconds 10 --seed 4 --bvh-out " + shellWord(dir)).status == 0);
    CHECK_FALSE(fs::exists(stale));
  }
  CHECK(r["poses"] == true);  // implied by --bvh-out
  const std::vector<std::string> names = {"avatar_000.bvh", "avatar_001.bvh", "avatar_002.bvh"};
  // Exactly these files and the manifest: nothing else, no scratch folder.
  std::vector<std::string> withManifest = names;
  withManifest.push_back("manifest.json");
  CHECK(entries(dir) == withManifest);
  CHECK(r["bvh_manifest"] == (dir / "manifest.json").string());
  REQUIRE(r["bvh_files"].is_array());
  REQUIRE(r["bvh_files"].size() == names.size());
  for (std::size_t i = 0; i < names.size(); ++i) CHECK(r["bvh_files"][i] == (dir / names[i]).string());
  CHECK(scratchLeft(box.dir()).empty());

  const auto frames = r["frames"].get<long long>();
  CHECK(frames == 300);
  for (const std::string& name : names) {
    CAPTURE(name);
    const Run inspected = box.run("inspect " + shellWord(dir / name) + " --json");
    const json report = inspected.report();
    REQUIRE(report["files"].size() == 1);
    const json& file = report["files"][0];
    CHECK(file["frames"] == frames);
    CHECK(file["fps"].get<double>() == Approx(r["fps"].get<double>()));
    CHECK(file["duration_s"].get<double>() == Approx(r["seconds"].get<double>()).margin(1.0 / 30));
  }
}

TEST_CASE("mgrl simulate --gltf-out writes one binary glTF per avatar, alone or beside the BVH",
          "[cli][data][simulate-cli]") {
  Sandbox box("gltf");
  box.trainPolicy();
  const fs::path alone = box.path("glb");
  const json r = box.simulate("--json --avatars 2 --seconds 4 --seed 5 --gltf-out " + shellWord(alone)).report();
  CHECK(r["poses"] == true);  // implied by --gltf-out
  CHECK(entries(alone) == std::vector<std::string>{"avatar_000.glb", "avatar_001.glb", "manifest.json"});
  CHECK(r["gltf_manifest"] == (alone / "manifest.json").string());
  REQUIRE(r["gltf_files"].size() == 2);
  CHECK_FALSE(r.contains("bvh_files"));
  const json manifest = json::parse(readText(alone / "manifest.json"));
  CHECK(manifest["format"] == "mgrl-simulate-output");
  REQUIRE(manifest["files"].size() == 2);
  for (const json& file : manifest["files"]) {
    CAPTURE(file);
    const std::string bytes = readText(alone / file["file"].get<std::string>());
    CHECK(file["bytes"] == bytes.size());
    CHECK(file["hash"] == mgrl::hexDigest(mgrl::hashBytes(bytes)));
    const json doc = json::parse(mgrl::splitGlb(bytes, file["file"].get<std::string>()).json);
    // One key per simulated frame, one node per joint besides the body.
    const int input = doc["animations"][0]["samplers"][0]["input"].get<int>();
    CHECK(doc["accessors"][input]["count"] == r["frames"]);
    CHECK(doc["nodes"].size() > 20);
    CHECK(doc["skins"][0]["joints"].size() == doc["nodes"].size() - 1);
  }
  // Sparring partners in different colours (the first avatar blue, the second orange), gloves red.
  CHECK(readText(alone / "avatar_000.glb") != readText(alone / "avatar_001.glb"));

  // The same folder as --bvh-out: one unit with both formats; the same seed, the same bytes.
  const fs::path both = box.path("both");
  const json r2 = box.simulate("--json --avatars 2 --seconds 4 --seed 5 --bvh-out " + shellWord(both) + " --gltf-out " +
                               shellWord(both / ""))
                      .report();
  CHECK(entries(both) == std::vector<std::string>{"avatar_000.bvh", "avatar_000.glb", "avatar_001.bvh",
                                                  "avatar_001.glb", "manifest.json"});
  CHECK(r2["bvh_files"].size() == 2);
  CHECK(r2["gltf_files"].size() == 2);
  CHECK(json::parse(readText(both / "manifest.json"))["files"].size() == 4);
  CHECK(readText(both / "avatar_000.glb") == readText(alone / "avatar_000.glb"));
  CHECK(scratchLeft(box.dir()).empty());

  // A file where the folder should be: refused, the file untouched, nothing left behind.
  const fs::path file = box.path("afile");
  std::ofstream(file) << "a file\n";
  requireRefusal(box.simulate("--json --avatars 2 --seconds 4 --gltf-out " + shellWord(file)),
                 "--gltf-out " + file.string(), "expected a folder, found another kind of file");
  CHECK(readText(file) == "a file\n");
  // An events file named like the folder's own files.
  requireRefusal(box.simulate("--json --avatars 2 --seconds 4 --gltf-out " + shellWord(alone) + " --events-out " +
                              shellWord(alone / "avatar_007.glb")),
                 "--events-out ", "expected a name other than the --gltf-out folder's own files");
  CHECK(scratchLeft(box.dir()).empty());
}

TEST_CASE("mgrl simulate repeats itself to the byte for a seed and differs for another", "[cli][data][simulate-cli]") {
  Sandbox box("seed");
  box.trainPolicy();
  auto simulate = [&](int seed, const std::string& tag, const std::string& extra = "") {
    return box
        .simulate("--json --avatars 2 --seconds 60 --seed " + std::to_string(seed) + " --events-out " +
                  shellWord(box.path(tag + ".jsonl")) + " --bvh-out " + shellWord(box.path(tag)) + " " + extra)
        .report();
  };
  const json first = simulate(7, "first");
  REQUIRE(first["hits"].get<long long>() > 0);
  const json second = simulate(7, "second");
  // The world promises the same events whatever the thread count.
  const json oneThread = simulate(7, "one_thread", "--threads 1");
  const json other = simulate(8, "other");
  REQUIRE(other["hits"].get<long long>() > 0);

  const std::string events = readText(box.path("first.jsonl"));
  REQUIRE_FALSE(events.empty());
  CHECK(readText(box.path("second.jsonl")) == events);
  CHECK(readText(box.path("one_thread.jsonl")) == events);
  CHECK(readText(box.path("other.jsonl")) != events);
  CHECK(second["hits"] == first["hits"]);
  CHECK(second["hits_by_avatar"] == first["hits_by_avatar"]);
  CHECK(second["hits_by_part"] == first["hits_by_part"]);
  CHECK(second["decisions"] == first["decisions"]);

  for (const char* name : {"avatar_000.bvh", "avatar_001.bvh"}) {
    CAPTURE(name);
    const std::string bvh = readText(box.path("first") / name);
    REQUIRE_FALSE(bvh.empty());
    CHECK(readText(box.path("second") / name) == bvh);
    CHECK(readText(box.path("one_thread") / name) == bvh);
    CHECK(readText(box.path("other") / name) != bvh);
  }
}

TEST_CASE("mgrl simulate refuses bad input before simulating and leaves nothing behind", "[cli][data][simulate-cli]") {
  Sandbox box("refuse");
  const fs::path bvh = box.path("bvh"), events = box.path("events.jsonl");
  const std::string outputs = " --bvh-out " + shellWord(bvh) + " --events-out " + shellWord(events);
  auto nothingWritten = [&]() {
    requireAbsent(bvh);
    requireAbsent(events);
    CHECK(scratchLeft(box.dir()).empty());
  };

  // Flags checked before anything is loaded.
  const std::vector<std::tuple<std::string, std::string, std::string>> flags = {
      {"--controller nonsense", "--controller: ", "expected one of: policy, online_search, random, found 'nonsense'"},
      {"--avatars 0", "--avatars: ", "found 0"},
      {"--avatars -3", "--avatars: ", "found -3"},
      {"--avatars 100000000", "--avatars: ", "found 100000000"},
      {"--seconds 0", "--seconds: ", "found 0"},
      {"--seconds -5", "--seconds: ", "found -5"},
      {"--top-k 100", "--top-k: ", "found 100"},
  };
  for (const auto& [arguments, start, detail] : flags) {
    CAPTURE(arguments);
    requireRefusal(box.simulate("--json " + arguments + outputs), start, detail);
    nothingWritten();
  }

  // No policy trained yet (the random controller would need none).
  requireRefusal(box.simulate("--json" + outputs), box.cache().string(), "no policy bundle here: run `mgrl train");
  nothingWritten();

  // A bundle without a behaviour the scenario asks for: named, before the graph is loaded.
  const fs::path partial = box.path("partial");
  {
    const Run trained = box.train("--behavior approach --out " + shellWord(partial));
    INFO("stderr: " << trained.err);
    REQUIRE(trained.status == 0);
  }
  REQUIRE(fs::is_regular_file(partial / "manifest.json"));
  requireRefusal(box.simulate("--json --policy " + shellWord(partial) + outputs), partial.string(),
                 "expected a trained table for behaviour 'hit' that the scenario asks for, found none");
  nothingWritten();

  // Output places that cannot be written (checked with the random controller: no bundle
  // needed, and no graph loaded before the refusal).
  const fs::path file = box.path("afile");
  std::ofstream(file) << "a file\n";
  const fs::path underFile = file / "out";
  requireRefusal(box.simulate("--json --controller random --bvh-out " + shellWord(underFile)),
                 "--bvh-out " + underFile.string(), "expected a folder that can be created");
  CHECK(readText(file) == "a file\n");
  requireRefusal(box.simulate("--json --controller random --bvh-out " + shellWord(file)), "--bvh-out " + file.string(),
                 "expected a folder");
  CHECK(readText(file) == "a file\n");

  const fs::path underAFile = file / "events.jsonl";
  requireRefusal(box.simulate("--json --controller random --events-out " + shellWord(underAFile)),
                 "--events-out " + file.string(), "expected a folder that can be created");
  CHECK(readText(file) == "a file\n");

  const fs::path folder = box.path("a_folder");
  fs::create_directory(folder);
  requireRefusal(box.simulate("--json --controller random --events-out " + shellWord(folder)),
                 "--events-out " + folder.string(), "expected a file name, found a folder");
  CHECK(fs::is_directory(folder));
  CHECK(fs::is_empty(folder));

  CHECK(scratchLeft(box.dir()).empty());
  CHECK(entries(box.dir()) == std::vector<std::string>{"a_folder", "afile", "cache", "partial"});
}

TEST_CASE("the trained policy lands far more hits than random actions", "[cli][data][simulate-cli]") {
  Sandbox box("versus");
  // Random actions need no trained bundle.
  const json random = box.simulate("--json --avatars 2 --seconds 120 --seed 1 --controller random").report();
  CHECK(random["controller"] == "random");
  CHECK_FALSE(random.contains("policy"));
  CHECK_FALSE(fs::exists(box.cache() / "policies"));

  box.trainPolicy();
  const json policy = box.simulate("--json --avatars 2 --seconds 120 --seed 1").report();
  CHECK(policy["controller"] == "policy");
  const double trained = policy["hits_per_avatar_minute"].get<double>();
  const double baseline = random["hits_per_avatar_minute"].get<double>();
  INFO("policy " << trained << " hits per avatar-minute, random " << baseline);
  CHECK(trained >= 3);
  CHECK(trained > 4 * baseline);
}

// A refusal after --bvh-out's folder would be made must not leave that folder behind.
TEST_CASE("a refused mgrl simulate leaves no --bvh-out folder behind", "[cli][data][simulate-cli]") {
  Sandbox box("leftover");
  SECTION("--events-out refused after --bvh-out was prepared") {
    const fs::path bvh = box.path("bvh"), folder = box.path("a_folder");
    fs::create_directory(folder);
    requireRefusal(box.simulate("--json --controller random --bvh-out " + shellWord(bvh) + " --events-out " +
                                shellWord(folder)),
                   "--events-out " + folder.string(), "expected a file name, found a folder");
    requireAbsent(bvh);
  }
  SECTION("a recording too large for memory") {
    const fs::path bvh = box.path("huge");
    const Run r = box.simulate("--json --controller random --avatars 200000 --seconds 86400 --bvh-out " +
                               shellWord(bvh));
    INFO("stderr: " << r.err);
    CHECK(r.status == 1);
    CHECK(r.out.empty());
    REQUIRE(lines(r.err).size() == 1);  // refused before the graph is loaded
    CHECK_THAT(lines(r.err).back(), StartsWith("mgrl: --bvh-out: recording 200000 avatars"));
    requireAbsent(bvh);
  }
}

// Output folders are handled one way: --events-out makes missing folders as
// --bvh-out does, and the text summary says where each output went.
TEST_CASE("mgrl simulate makes missing output folders and says where it wrote", "[cli][data][simulate-cli]") {
  Sandbox box("outputs");
  const fs::path bvh = box.path("new") / "bvh", events = box.path("other") / "deeper" / "hits.jsonl";
  const Run r = box.simulate("--controller random --avatars 1 --seconds 1 --bvh-out " + shellWord(bvh) +
                             " --events-out " + shellWord(events));
  INFO("stderr: " << r.err);
  REQUIRE(r.status == 0);
  CHECK(fs::is_regular_file(bvh / "avatar_000.bvh"));
  CHECK(fs::is_regular_file(events));
  const std::vector<std::string> summary = lines(r.out);
  REQUIRE(summary.size() == 4);
  // One avatar: singular words, and a wall time that never reads "0.00 s".
  CHECK_THAT(summary[0], StartsWith("simulate (random controller, sparring): 1 avatar x 30 frames (1.0 s) in "));
  CHECK_THAT(summary[0], !Contains("in 0.00 s"));
  CHECK(summary[2] == "wrote 1 BVH file to " + bvh.string());
  CHECK(summary[3] == "wrote the hits to " + events.string());
  CHECK(scratchLeft(box.dir()).empty());
}

// ---------------------------------------------------------------------------------------
// --bvh-out's folder is one unit, all from one run, with a manifest
// naming the run; a killed run leaves the old folder or the new one, never a mix.

namespace {

// A pid that no longer exists (a child that has exited and been reaped).
pid_t deadPid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

// Checks that `dir` is one whole simulate output: a sealed manifest, exactly the files it
// lists (and nothing else), each with its listed size and hash. Returns the manifest.
json requireWholeOutput(const fs::path& dir) {
  INFO("folder: " << dir);
  REQUIRE(fs::is_regular_file(dir / "manifest.json"));
  const json manifest = json::parse(readText(dir / "manifest.json"));
  CHECK(manifest["format"] == "mgrl-simulate-output");
  CHECK(manifest["version"] == 1);
  REQUIRE_NOTHROW(mgrl::checkManifestHash(manifest, mgrl::ManifestReader((dir / "manifest.json").string())));
  std::vector<std::string> listed = {"manifest.json"};
  for (const json& file : manifest["files"]) {
    const std::string name = file["file"].get<std::string>();
    CAPTURE(name);
    listed.push_back(name);
    const std::string bytes = readText(dir / name);
    CHECK(bytes.size() == file["bytes"].get<std::size_t>());
    CHECK(mgrl::hexDigest(mgrl::hashBytes(bytes)) == file["hash"].get<std::string>());
  }
  std::sort(listed.begin(), listed.end());
  CHECK(entries(dir) == listed);
  return manifest;
}

}  // namespace

TEST_CASE("mgrl simulate --bvh-out replaces its folder whole, with a manifest naming the run",
          "[cli][data][simulate-cli][robustness]") {
  Sandbox box("unit");
  const fs::path dir = box.path("out");
  const std::string common = "--json --controller random --seconds 2 --bvh-out " + shellWord(dir);

  // Three avatars, the events inside the folder: they belong to it.
  const json first = box.simulate(common + " --avatars 3 --seed 4 --events-out " + shellWord(dir / "hits.jsonl")).report();
  json manifest = requireWholeOutput(dir);
  CHECK(manifest["run"]["seed"] == 4);
  CHECK(manifest["run"]["avatars"] == 3);
  CHECK(manifest["run"]["controller"] == "random");
  CHECK(manifest["run"]["scenario"] == first["scenario"]);
  CHECK(manifest["run"]["time_utc"].is_string());
  CHECK(manifest["files"].size() == 4);  // three avatars and hits.jsonl
  CHECK_FALSE(manifest.contains("events_out"));

  // Two avatars now: the old code moved two files over the old ones and left avatar_002.bvh
  // and the old hits.jsonl, a mix of two runs with nothing to tell.
  box.simulate(common + " --avatars 2 --seed 5").report();
  manifest = requireWholeOutput(dir);
  CHECK(manifest["run"]["seed"] == 5);
  CHECK(entries(dir) == std::vector<std::string>{"avatar_000.bvh", "avatar_001.bvh", "manifest.json"});

  // Events elsewhere: the manifest has their hash, so a stale events file can be told.
  const fs::path events = box.path("events.jsonl");
  box.simulate(common + " --avatars 2 --seed 6 --events-out " + shellWord(events)).report();
  manifest = requireWholeOutput(dir);
  REQUIRE(manifest.contains("events_out"));
  CHECK(manifest["events_out"]["path"] == fs::absolute(events).lexically_normal().string());
  CHECK(manifest["events_out"]["hash"] == mgrl::hexDigest(mgrl::hashBytes(readText(events))));
  CHECK(scratchLeft(box.dir()).empty());

  SECTION("what killed runs left beside the folder goes; a live run's stays") {
    const pid_t dead = deadPid();
    const fs::path halfWritten = box.path("out.tmp-" + std::to_string(dead) + "-0");
    const fs::path replaced = box.path("out.old-" + std::to_string(dead) + "-1");
    const fs::path live = box.path("out.tmp-" + std::to_string(::getpid()) + "-7");
    for (const fs::path& p : {halfWritten, replaced, live}) {
      fs::create_directories(p);
      std::ofstream(p / "avatar_000.bvh") << "half";
    }
    fs::copy_file(dir / "manifest.json", replaced / "manifest.json");
    box.simulate(common + " --avatars 1 --seed 7").report();
    CHECK(requireWholeOutput(dir)["run"]["seed"] == 7);
    requireAbsent(halfWritten);
    requireAbsent(replaced);
    CHECK(fs::exists(live));
    fs::remove_all(live);
  }
  SECTION("a complete folder a killed run left beside a missing one is put back, then replaced") {
    const fs::path complete = box.path("out.tmp-" + std::to_string(deadPid()) + "-0");
    fs::rename(dir, complete);
    box.simulate(common + " --avatars 1 --seed 8").report();
    CHECK(requireWholeOutput(dir)["run"]["seed"] == 8);
    requireAbsent(complete);
  }
  SECTION("a folder written before manifests existed is replaced") {
    fs::remove_all(dir);
    fs::create_directories(dir / ".mgrl-simulate-1");
    for (const char* name : {"avatar_000.bvh", "avatar_001.bvh", "hits.jsonl"}) std::ofstream(dir / name) << "old";
    box.simulate(common + " --avatars 1 --seed 9").report();
    CHECK(requireWholeOutput(dir)["run"]["seed"] == 9);
  }
  SECTION("a folder holding anything else is refused before simulating, untouched") {
    std::ofstream(dir / "notes.txt") << "mine\n";
    requireRefusal(box.simulate(common + " --avatars 1 --seed 10"), "--bvh-out " + dir.string(),
                   "expected a simulate output (with manifest.json) or an empty directory to replace, found a "
                   "directory with other files; not deleting it");
    CHECK(readText(dir / "notes.txt") == "mine\n");
    CHECK(manifest == json::parse(readText(dir / "manifest.json")));
  }
  SECTION("the events file may not take the name of one of the folder's own files") {
    requireRefusal(box.simulate(common + " --avatars 1 --events-out " + shellWord(dir / "manifest.json")),
                   "--events-out " + (dir / "manifest.json").string(), "expected a name other than");
    CHECK(manifest == json::parse(readText(dir / "manifest.json")));
  }
  CHECK(scratchLeft(box.dir()).empty());
}

// SIGKILL at random moments of runs that each replace the folder: whatever the moment, the
// folder is one whole run's (the old or the new), and the next run cleans what was left.
TEST_CASE("mgrl simulate killed at any moment leaves --bvh-out whole, old or new", "[cli][data][simulate-cli][robustness]") {
  Sandbox box("kill");
  const fs::path dir = box.path("out");
  const std::string arguments = "simulate " + shellWord(kBoxing) + box.where() + " " + kFast +
                                " --json --controller random --seconds 20 --bvh-out " + shellWord(dir);
  // The first run builds the graph and gives the folder something to replace.
  const auto start = std::chrono::steady_clock::now();
  REQUIRE(box.run(arguments + " --avatars 3 --seed 1").status == 0);
  const auto timed = std::chrono::steady_clock::now();
  REQUIRE(box.run(arguments + " --avatars 3 --seed 1").status == 0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - timed).count();
  (void)start;
  requireWholeOutput(dir);

  std::mt19937 random(19);
  std::set<std::uint64_t> seen = {1};
  int killedMidway = 0;
  for (int round = 0; round < 12; ++round) {
    const std::uint64_t seed = 100 + static_cast<std::uint64_t>(round);
    const int avatars = 1 + round % 4;
    const double delay = std::uniform_real_distribution<double>(0.3, 1.05)(random) * seconds;
    CAPTURE(round, seed, avatars, delay);
    const std::string command = std::string(MGRL_BINARY) + " " + arguments + " --avatars " + std::to_string(avatars) +
                                " --seed " + std::to_string(seed) + " >/dev/null 2>&1";
    const pid_t child = ::fork();
    if (child == 0) {
      ::execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(delay));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    const bool killed = WIFSIGNALED(status);
    const json manifest = requireWholeOutput(dir);
    const auto made = manifest["run"]["seed"].get<std::uint64_t>();
    // The new run's, or one that ran to the end before.
    CHECK((made == seed || seen.count(made) == 1));
    if (made == seed) CHECK(manifest["files"].size() == static_cast<std::size_t>(avatars));
    if (!killed) seen.insert(seed);
    if (killed && made != seed) ++killedMidway;
    if (made == seed) seen.insert(seed);
  }
  INFO("runs killed before their folder was in place: " << killedMidway);
  CHECK(killedMidway > 0);
  // The next run cleans what the killed ones left.
  REQUIRE(box.run(arguments + " --avatars 2 --seed 2").status == 0);
  CHECK(requireWholeOutput(dir)["run"]["seed"] == 2);
  CHECK(scratchLeft(box.dir()).empty());
}

}  // namespace cli_simulate_test
