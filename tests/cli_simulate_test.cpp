// `mgrl simulate` through the real binary (DESIGN.md sec. 5; app/simulate_command.cpp): the
// --json report and the text summary, the hit events as JSON lines, one BVH per avatar,
// determinism for a seed, refusals (exit 1, one line on stderr, nothing on stdout, no
// output left behind, no simulation started) and the trained policy against random
// actions. Each test trains the boxing scenario with small budgets (a second or two) in a
// cache folder of its own.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.hpp"
#include "test_support.hpp"

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

// Every file or folder under `dir` whose name starts with the scratch prefix.
std::vector<std::string> scratchLeft(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& item : fs::recursive_directory_iterator(dir))
    if (item.path().filename().string().rfind(kScratchPrefix, 0) == 0) found.push_back(item.path().string());
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
  for (const char* key : {"time", "attacker", "target", "hand", "speed", "part", "point"}) CHECK(e.contains(key));
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

TEST_CASE("mgrl simulate --json prints one report object; without it, a text summary", "[cli][data][simulate-cli]") {
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

  {  // sparring: every punch lands on the partner
    const fs::path file = box.path("hits.jsonl");
    const json r = box.simulate("--json --avatars 2 --seconds 60 --seed 2 --events-out " + shellWord(file)).report();
    CHECK(r["events_file"] == file.string());
    const auto hits = r["hits"].get<std::size_t>();
    REQUIRE(hits > 0);
    const std::vector<json> events = readEvents(file);
    REQUIRE(events.size() == hits);

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
      ++byAttacker[static_cast<std::size_t>(attacker)];
      CHECK(e["target"].get<long long>() == 1 - attacker);  // the pair's other boxer, never -1 here
      const std::string part = e["part"].get<std::string>();
      CHECK((part == "head" || part == "chest" || part == "spine"));
      ++byPart[part];
    }
    CHECK(json(byAttacker) == r["hits_by_avatar"]);
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
    // Issue 19, defect 5: a killed run's scratch folder (its process gone) goes with the
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
  // Exactly these files: nothing else, no scratch folder.
  CHECK(entries(dir) == names);
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

// Output folders are handled one way (issue 12): --events-out makes missing folders as
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
