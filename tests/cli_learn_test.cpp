// `mgrl list`, `mgrl train` and `mgrl eval` through the real binary (DESIGN.md sec. 5-6):
// the --json reports, the policy bundle on disk, determinism, retraining one behaviour,
// resuming from a checkpoint, and refusals (non-zero exit, nothing on stdout, the reason on
// stderr). Each test trains the boxing scenario with small budgets (about a second) in a
// cache folder of its own.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.hpp"
#include "mgrl/core/bundle.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_learn_test {

namespace fs = std::filesystem;
using Catch::Contains;
using Catch::StartsWith;
using nlohmann::json;

namespace {

const std::string kBoxing = std::string(MGRL_SOURCE_DIR) + "/scenarios/boxing.yaml";
// Budgets that train boxing in about a second (the file asks for 5 M and 20 M updates).
const std::string kFast = "--set behaviors.approach.learner.budget=200000 --set behaviors.hit.learner.budget=400000";
// kFast with checkpoints: the approach behaviour saves one every 100 k of its 300 k updates.
const std::string kCheckpointed =
    "--set behaviors.approach.learner.budget=300000 "
    "--set behaviors.approach.learner.checkpoint_every=100000 "
    "--set behaviors.hit.learner.budget=400000";

using mgrl::test::lines;
using mgrl::test::readText;
using mgrl::test::Run;
using mgrl::test::shellWord;

// A fresh folder per test (cache, bundles, captured streams), removed at the end even when
// the test fails.
class Sandbox : public mgrl::test::CliSandbox {
 public:
  explicit Sandbox(const std::string& tag) : CliSandbox("mgrl_cli_learn_" + tag) {}

  // Runs mgrl with `arguments` (shell words), `environment` ("NAME=value ...") added to a
  // copy of ours without MGRL_EXIT_AFTER_CHECKPOINTS.
  Run run(const std::string& arguments, const std::string& environment = "") {
    return mgrl::test::runMgrl(arguments, dir(), "env -u MGRL_EXIT_AFTER_CHECKPOINTS " + environment);
  }

  Run train(const std::string& arguments, const std::string& environment = "") {
    return run("train " + shellWord(kBoxing) + " --json" + where() + " " + arguments, environment);
  }
  Run eval(const std::string& arguments) {
    return run("eval " + shellWord(kBoxing) + " --json" + where() + " " + arguments);
  }
};

// The refusal contract: exit 1, nothing on stdout, and the reason as the last line of
// stderr, "mgrl: ..." (the test at the end checks that it is the only line when the
// refusal needs no graph).
void requireRefusal(const Run& r, const std::string& reason) {
  INFO("stderr: " << r.err);
  CHECK(r.status == 1);
  CHECK(r.out.empty());
  CHECK_THAT(r.lastErrorLine(), StartsWith("mgrl: ") && Contains(reason));
}

// The same, for refusals that come before any work: the reason is all there is on stderr.
void requireOneLineRefusal(const Run& r, const std::string& reason) {
  requireRefusal(r, reason);
  CHECK(lines(r.err).size() == 1);
}

void requireFile(const fs::path& p) {
  INFO(p);
  CHECK(fs::is_regular_file(p));
}

}  // namespace

TEST_CASE("mgrl list names every plugin, as text and as JSON", "[cli]") {
  Sandbox box("list");
  const Run text = box.run("list");
  INFO(text.err);
  REQUIRE(text.status == 0);
  CHECK(text.err.empty());
  for (const char* name :
       {"polar2d", "cylindrical3d", "approach", "hit", "static_target", "q_learning", "value_iteration"})
    CHECK_THAT(text.out, Contains(std::string("  ") + name + ": "));
  CHECK_THAT(text.out, Contains("budget") && Contains("default 10000000") && Contains("contact_radius"));

  const Run run = box.run("list --json");
  const json list = run.report();
  CHECK(run.err.empty());
  const std::vector<std::pair<const char*, std::vector<std::string>>> seams = {
      {"discretizers", {"polar2d", "cylindrical3d"}},
      {"rewards", {"approach", "hit"}},
      {"environments", {"static_target"}},
      {"learners", {"q_learning", "value_iteration"}}};
  CHECK(list.size() == seams.size() + 4);  // plus the reward and success terms, the controllers and the world section
  REQUIRE(list["reward_terms"].is_array());
  std::vector<std::string> terms;
  for (const json& term : list["reward_terms"]) terms.push_back(term["name"]);
  CHECK(terms ==
        std::vector<std::string>{"distance", "facing", "contact", "travel", "effort", "avoid", "struck", "reversal"});
  CHECK_THAT(text.out, Contains("  term: contact  ") && Contains("success (behaviors.NAME.success"));
  // The success terms are the reward terms that register a condition, with its threshold.
  std::vector<std::string> conditions;
  for (const json& condition : list["success_terms"]) conditions.push_back(condition["name"]);
  CHECK(conditions == std::vector<std::string>{"distance", "facing", "contact", "avoid"});
  CHECK_THAT(text.out, Contains("success terms (behaviors.NAME.success.term):") && Contains("within_deg"));
  CHECK(list["controllers"] == json::array({"policy", "online_search", "random"}));
  REQUIRE(list["world"].is_array());
  CHECK(list["world"].size() == 27);  // stance_hold the latest
  for (const json& p : list["world"])
    for (const char* key : {"name", "default", "range", "unit", "help"}) CHECK(p.contains(key));
  for (const auto& [seam, names] : seams) {
    CAPTURE(seam);
    REQUIRE(list[seam].is_array());
    std::vector<std::string> found;
    for (const json& entry : list[seam]) {
      found.push_back(entry["name"].get<std::string>());
      CHECK(entry["summary"].is_string());
      REQUIRE(entry["parameters"].is_array());
      for (const json& p : entry["parameters"])
        for (const char* key : {"name", "default", "range", "unit", "help"}) CHECK(p.contains(key));
    }
    for (const std::string& name : names) CHECK(std::find(found.begin(), found.end(), name) != found.end());
  }
}

TEST_CASE("mgrl train --json reports each behaviour and writes the same bundle every time", "[cli][data]") {
  Sandbox box("train");
  const fs::path out = box.path("bundle");
  const Run first = box.train(kFast + " --out " + shellWord(out));
  const json report = first.report();
  CHECK(report["policy"] == out.string());
  CHECK(report["graph_key"].is_string());
  REQUIRE(report["behaviors"].size() == 2);
  for (const auto& [name, updates] : {std::pair{"approach", 200000}, std::pair{"hit", 400000}}) {
    CAPTURE(name);
    const json& b = report["behaviors"][name];
    for (const char* key : {"learner", "updates", "seconds", "updates_per_second", "final_residual", "table_bytes"})
      CHECK(b.contains(key));
    CHECK(b["learner"] == "q_learning");
    CHECK(b["updates"] == updates);
    CHECK(b["seconds"].get<double>() > 0);
    CHECK(b["updates_per_second"].get<double>() > 0);
    CHECK(b["final_residual"].get<double>() >= 0);
    // One float32 per (action, vertex).
    CHECK(b["table_bytes"].get<std::uint64_t>() ==
          4 * b["actions"].get<std::uint64_t>() * b["vertices"].get<std::uint64_t>());
  }
  CHECK(report["behaviors"]["approach"]["vertices"] == 5 * 13);
  CHECK(report["behaviors"]["hit"]["vertices"] == 20 * 16 * 6);

  for (const char* file : {"manifest.json", "approach.q.npy", "hit.q.npy"}) requireFile(out / file);
  const std::string approach = readText(out / "approach.q.npy"), hit = readText(out / "hit.q.npy");
  CHECK(approach.rfind("\x93NUMPY", 0) == 0);
  const json manifest = json::parse(readText(out / "manifest.json"));
  CHECK(manifest.is_object());
  // Nothing left behind: no checkpoints, no temporary folder beside the bundle.
  CHECK_FALSE(fs::exists(box.path("bundle.checkpoints")));
  for (const auto& item : fs::directory_iterator(box.dir()))
    CHECK_THAT(item.path().filename().string(), !Contains("bundle."));

  // The same command, the same tables, to the byte.
  const Run second = box.train(kFast + " --out " + shellWord(out));
  REQUIRE(second.status == 0);
  CHECK(readText(out / "approach.q.npy") == approach);
  CHECK(readText(out / "hit.q.npy") == hit);
}

TEST_CASE("mgrl train --behavior retrains one behaviour and keeps the other's table", "[cli][data]") {
  Sandbox box("behavior");
  const fs::path out = box.path("bundle");
  REQUIRE(box.train(kFast + " --out " + shellWord(out)).status == 0);
  const std::string approach = readText(out / "approach.q.npy"), hit = readText(out / "hit.q.npy");

  const std::string reseeded = kFast + " --set behaviors.hit.learner.seed=2";
  const json report = box.train(reseeded + " --behavior hit --out " + shellWord(out)).report();
  REQUIRE(report["behaviors"].size() == 1);
  CHECK(report["behaviors"].contains("hit"));
  CHECK(readText(out / "approach.q.npy") == approach);
  CHECK(readText(out / "hit.q.npy") != hit);
  // The bundle now holds both behaviours as the reseeded scenario asks for them.
  const Run eval = box.eval(reseeded + " --trials 5 --policy " + shellWord(out));
  INFO(eval.err);
  CHECK(eval.status == 0);

  const std::string retrained = readText(out / "hit.q.npy");
  requireRefusal(box.train(kFast + " --behavior nope --out " + shellWord(out)),
                 "--behavior: expected one of the scenario's behaviours (approach, hit), found 'nope'");
  CHECK(readText(out / "hit.q.npy") == retrained);  // the refused run left the bundle alone
  CHECK(readText(out / "approach.q.npy") == approach);
}

TEST_CASE("an interrupted mgrl train resumes to the table of an uninterrupted run", "[cli][data]") {
  Sandbox box("resume");
  const fs::path out = box.path("resumed"), checkpoint = box.path("resumed.checkpoints") / "approach";

  const Run killed = box.train(kCheckpointed + " --out " + shellWord(out), "MGRL_EXIT_AFTER_CHECKPOINTS=1");
  INFO(killed.err);
  CHECK(killed.status == 75);
  CHECK(killed.out.empty());
  CHECK_THAT(killed.err, Contains("exiting after checkpoint 1"));
  requireFile(checkpoint / "state.json");
  requireFile(checkpoint / "table.npy");
  CHECK_FALSE(fs::exists(out));  // never half a bundle

  const Run resume = box.train(kCheckpointed + " --resume --out " + shellWord(out));
  const json resumed = resume.report();
  CHECK_THAT(resume.err, !Contains("ignoring the checkpoint"));
  CHECK(resumed["behaviors"]["approach"]["stats"]["resumed"] == true);
  CHECK(resumed["behaviors"]["approach"]["updates"] == 300000);
  CHECK(resumed["behaviors"]["hit"]["stats"]["resumed"] == false);
  CHECK_FALSE(fs::exists(box.path("resumed.checkpoints")));  // done with

  const fs::path straight = box.path("straight");
  const json uninterrupted = box.train(kCheckpointed + " --out " + shellWord(straight)).report();
  CHECK(uninterrupted["behaviors"]["approach"]["stats"]["resumed"] == false);
  CHECK(readText(out / "approach.q.npy") == readText(straight / "approach.q.npy"));
  CHECK(readText(out / "hit.q.npy") == readText(straight / "hit.q.npy"));
  CHECK(resumed["behaviors"]["approach"]["stats"]["restarts"] ==
        uninterrupted["behaviors"]["approach"]["stats"]["restarts"]);
}

TEST_CASE("mgrl train starts over without --resume or from a checkpoint of other settings", "[cli][data]") {
  Sandbox box("discard");
  const fs::path out = box.path("bundle"), checkpoints = box.path("bundle.checkpoints");
  const std::string train = kCheckpointed + " --out " + shellWord(out);

  SECTION("without --resume the checkpoint is discarded") {
    REQUIRE(box.train(train, "MGRL_EXIT_AFTER_CHECKPOINTS=1").status == 75);
    REQUIRE(fs::exists(checkpoints / "approach" / "state.json"));
    const Run again = box.train(train);
    INFO(again.err);
    CHECK(again.report()["behaviors"]["approach"]["stats"]["resumed"] == false);
    // Nothing is said about checkpoints unless one is refused (mgrl/learning/checkpoint_store.hpp).
    CHECK_THAT(again.err, !Contains("resum") && !Contains("ignoring the checkpoint"));
    CHECK_FALSE(fs::exists(checkpoints));
  }
  SECTION("--resume ignores, and says so, a checkpoint of other settings") {
    REQUIRE(box.train(train, "MGRL_EXIT_AFTER_CHECKPOINTS=1").status == 75);
    const Run other = box.train(train + " --resume --set behaviors.approach.learner.seed=2");
    INFO(other.err);
    CHECK(other.report()["behaviors"]["approach"]["stats"]["resumed"] == false);
    CHECK_THAT(other.err, Contains("a checkpoint of other inputs or settings") && Contains("ignoring the checkpoint"));
    CHECK_FALSE(fs::exists(checkpoints));
  }
  SECTION("--resume without a checkpoint trains from the start") {
    const Run fresh = box.train(train + " --resume");
    INFO(fresh.err);
    CHECK(fresh.report()["behaviors"]["approach"]["stats"]["resumed"] == false);
  }
}

// Found by the kill tests (scripts/kill_test.py): a run killed after its bundle was in place
// but before it removed its checkpoints left `<out>.checkpoints/` (22 MB per behaviour at
// the scenario's budgets), and a killed checkpoint save left `<behaviour>.tmp-PID-N` beside
// it. The next `--resume` found every behaviour trained, kept them, and never touched the
// checkpoints: they stayed for good. A finished run removes the checkpoints of every
// behaviour it was asked for, kept ones included, and what killed writers left there.
TEST_CASE("mgrl train --resume that keeps every behaviour removes the checkpoints a killed run left", "[cli][data]") {
  Sandbox box("kept-checkpoints");
  const fs::path out = box.path("bundle"), checkpoints = box.path("bundle.checkpoints");
  const std::string train = kCheckpointed + " --out " + shellWord(out);
  REQUIRE(box.train(train, "MGRL_EXIT_AFTER_CHECKPOINTS=1").status == 75);
  REQUIRE(fs::exists(checkpoints / "approach" / "state.json"));
  fs::copy(checkpoints, box.path("saved"), fs::copy_options::recursive);
  REQUIRE(box.train(train).status == 0);
  REQUIRE_FALSE(fs::exists(checkpoints));
  // What a run killed between putting its bundle in place and removing its checkpoints
  // leaves, with a checkpoint save of a process that is gone.
  fs::copy(box.path("saved"), checkpoints, fs::copy_options::recursive);
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  int status = 0;
  ::waitpid(gone, &status, 0);
  fs::copy(checkpoints / "approach", checkpoints / ("approach.tmp-" + std::to_string(gone) + "-0"));

  const Run resume = box.train(train + " --resume");
  const json report = resume.report();
  CHECK(report["kept"] == json::array({"approach", "hit"}));
  CHECK_FALSE(fs::exists(checkpoints));
}

// Found by the kill tests: train checks that --out's folder takes a file by writing
// `.<out>.probe-PID` and removing it; killed in between, it left the probe for good. The
// next run removes those of processes that are gone (a live one may be training now).
TEST_CASE("mgrl train removes the writability probe a killed run left beside --out", "[cli][data]") {
  Sandbox box("probe");
  const fs::path out = box.path("bundle");
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  int status = 0;
  ::waitpid(gone, &status, 0);
  const fs::path dead = box.path(".bundle.probe-" + std::to_string(gone));
  const fs::path live = box.path(".bundle.probe-" + std::to_string(::getpid()));
  const fs::path other = box.path(".other.probe-" + std::to_string(gone));
  for (const fs::path& p : {dead, live, other}) std::ofstream(p) << "x";

  REQUIRE(box.train(kFast + " --out " + shellWord(out)).status == 0);
  CHECK_FALSE(fs::exists(dead));
  CHECK(fs::exists(live));
  CHECK(fs::exists(other));  // another bundle's
}

TEST_CASE("settings left out of the behaviour key do not change the trained table", "[cli][data]") {
  // checkpoint_every, curve_points and threads are not hashed into the key (mgrl/learning/behavior.hpp),
  // so a bundle trained with other values is taken as current: its table must be the same.
  Sandbox box("unkeyed");
  const fs::path a = box.path("a"), b = box.path("b");
  REQUIRE(box.train(kFast + " --behavior approach --out " + shellWord(a)).status == 0);
  const Run other = box.train(kFast +
                              " --set behaviors.approach.learner.checkpoint_every=70000"
                              " --set behaviors.approach.learner.curve_points=3"
                              " --set behaviors.approach.learner.threads=1 --behavior approach --out " +
                              shellWord(b));
  REQUIRE(other.status == 0);
  CHECK(readText(a / "approach.q.npy") == readText(b / "approach.q.npy"));
}

TEST_CASE("mgrl eval --json reports the contract keys and repeats itself for a seed", "[cli][data]") {
  Sandbox box("eval");
  // The default bundle location, in the cache, on both sides.
  REQUIRE(box.train(kFast).status == 0);
  const std::string args = kFast + " --trials 40 --seed 5";
  json first = box.eval(args).report();
  json second = box.eval(args).report();
  for (const char* key : {"success_rate", "mean_time_to_hit_s", "median_time_to_hit_s", "mean_return",
                          "decisions_per_second", "random_baseline"})
    CHECK(first.contains(key));
  CHECK_THAT(first["policy"].get<std::string>(), StartsWith(box.cache().string()));
  CHECK(first["trials"] == 40);
  CHECK(first["seed"] == 5);
  const double rate = first["success_rate"].get<double>();
  CHECK(rate >= 0);
  CHECK(rate <= 1);
  CHECK(first["decisions_per_second"].get<double>() > 0);
  const json& baseline = first["random_baseline"];
  for (const char* key : {"success_rate", "mean_time_to_hit_s", "median_time_to_hit_s", "mean_return"})
    CHECK(baseline.contains(key));
  // Trained for a second, the policy already lands more punches than random actions.
  CHECK(rate > baseline["success_rate"].get<double>());
  if (!first["mean_time_to_hit_s"].is_null()) {
    CHECK(first["mean_time_to_hit_s"].get<double>() > 0);
    CHECK(first["mean_time_to_hit_s"].get<double>() <= first["seconds_per_trial"].get<double>());
  }

  // Timings differ from run to run; everything else repeats.
  CHECK(first["startup_seconds"].get<double>() > 0);
  CHECK(first["startup_seconds"].get<double>() < 30);
  for (const char* timing : {"decisions_per_second", "startup_seconds"}) {
    first.erase(timing);
    second.erase(timing);
  }
  CHECK(first == second);
}

TEST_CASE("mgrl eval --controller random needs no trained bundle", "[cli][data]") {
  Sandbox box("random");
  const json report = box.eval(kFast + " --controller random --trials 10 --seed 3").report();
  CHECK(report["controller"] == "random");
  CHECK(report["trials"] == 10);
  for (const char* key :
       {"success_rate", "mean_time_to_hit_s", "median_time_to_hit_s", "mean_return", "decisions_per_second"})
    CHECK(report.contains(key));
  CHECK_FALSE(report.contains("random_baseline"));
  CHECK_FALSE(fs::exists(box.cache() / "policies"));
}

TEST_CASE("mgrl eval --controller online_search searches the graph without a trained bundle", "[cli][data]") {
  Sandbox box("search");
  const json report = box.eval(kFast + " --controller online_search --horizon 2 --trials 8 --seed 3").report();
  CHECK(report["controller"] == "online_search");
  CHECK(report["horizon"] == 2);
  for (const char* key : {"success_rate", "mean_time_to_hit_s", "median_time_to_hit_s", "mean_return",
                          "decisions_per_second", "random_baseline"})
    CHECK(report.contains(key));
  // A depth-2 search expands the first state's actions and theirs: more than one level.
  CHECK(report["mean_expanded_actions"].get<double>() > 20);
  CHECK(report["mean_return"].get<double>() > report["random_baseline"]["mean_return"].get<double>());
  CHECK_FALSE(fs::exists(box.cache() / "policies"));
  // The same seed, the same numbers.
  const json again = box.eval(kFast + " --controller online_search --horizon 2 --trials 8 --seed 3").report();
  for (const char* key : {"success_rate", "mean_time_to_hit_s", "mean_return", "mean_expanded_actions"})
    CHECK(again[key] == report[key]);
}

TEST_CASE("mgrl train and eval refuse what they cannot use, with the reason on stderr", "[cli][data]") {
  Sandbox box("refuse");
  const fs::path out = box.path("bundle");

  // Checked before any work: the reason is the only line.
  requireOneLineRefusal(box.eval(kFast + " --trials 0"),
                        "--trials: expected a number of trials in [1, 10000000], found 0");
  requireOneLineRefusal(box.eval(kFast + " --controller bogus"),
                        "--controller: expected one of: policy, online_search, random, found 'bogus'");
  requireOneLineRefusal(box.eval(kFast + " --controller online_search --horizon 0"),
                        "--horizon: expected a search depth in actions in [1, 8], found 0");
  for (const char* command : {"train", "eval"}) {
    CAPTURE(command);
    requireOneLineRefusal(
        box.run(std::string(command) + " " + shellWord(kBoxing) + " --json" + box.where() + " --set nokey"),
        "mgrl: " + kBoxing +
            ": --set 'nokey': expected KEY=VALUE with a dotted KEY such as "
            "behaviors.hit.learner.budget");
    // Plugin parameters are checked before the graph is built or loaded.
    requireRefusal(box.run(std::string(command) + " " + shellWord(kBoxing) + " --json" + box.where() +
                           " --set behaviors.hit.learner.budget=lots"),
                   "behaviors.hit.learner.budget: expected a whole number in [1, 1000000000000], found 'lots'");
  }

  // Nothing trained yet.
  requireRefusal(box.eval(kFast), "no policy bundle here: run `mgrl train");
  requireRefusal(box.eval(kFast + " --policy " + shellWord(out)), out.string() + ": no policy bundle here");

  // --out must be a folder or nothing.
  const fs::path file = box.path("file.txt");
  std::ofstream(file) << "not a bundle\n";
  requireRefusal(box.train(kFast + " --out " + shellWord(file)),
                 "--out " + file.string() + ": expected a policy bundle directory or nothing, found a file");
  CHECK(readText(file) == "not a bundle\n");

  REQUIRE(box.train(kFast + " --out " + shellWord(out)).status == 0);
  REQUIRE(box.eval(kFast + " --trials 3 --policy " + shellWord(out)).status == 0);
  // Another reward parameter: without --policy, the scenario's own bundle (for these
  // settings) does not exist; with --policy, the bundle's settings are used, saying so.
  requireRefusal(box.eval(kFast + " --set behaviors.approach.reward.sigma=0.2"), "no policy bundle here");
  const Run adopted = box.eval(kFast + " --trials 3 --set behaviors.approach.reward.sigma=0.2 --policy " + shellWord(out));
  INFO(adopted.err);
  CHECK(adopted.status == 0);
  CHECK_THAT(adopted.err, Contains("--policy " + out.string() + ": using the settings the bundle was trained with "
                                   "(approach.reward.sigma=0.1) instead of the scenario's"));
  // Another graph.
  requireRefusal(box.eval(kFast + " --set graph.threshold=0.5 --policy " + shellWord(out)),
                 "the policy was made for another graph");
  // A bundle without one of the scenario's behaviours.
  const fs::path partial = box.path("partial");
  REQUIRE(box.train(kFast + " --behavior hit --out " + shellWord(partial)).status == 0);
  requireRefusal(box.eval(kFast + " --policy " + shellWord(partial)),
                 "expected a trained table for behaviour 'approach' that the scenario asks for, found none; run mgrl "
                 "train");
}

// DESIGN.md sec. 5 and tests/run_cli.cmake: on an error, one line on stderr. A missing
// bundle and a bad plugin parameter are found before the graph is built or loaded, so no
// graph-cache log line ("mgrl: graph: ...") comes before the reason.
TEST_CASE("refusals that need no graph print only the reason on stderr", "[cli][data]") {
  Sandbox box("oneline");
  const Run missing = box.eval(kFast);
  INFO(missing.err);
  CHECK(missing.status == 1);
  CHECK(lines(missing.err).size() == 1);
  const Run badParameter = box.train("--set behaviors.hit.learner.budget=lots");
  INFO(badParameter.err);
  CHECK(badParameter.status == 1);
  CHECK(lines(badParameter.err).size() == 1);
}

// Ctrl-C (here raised by MGRL_STOP_AFTER_CHECKPOINTS, as the signal handler
// does) keeps the finished behaviours, saves a checkpoint, says how to resume; the bundle
// is not taken for a whole one; --resume says what it resumed and ends with the table of
// an uninterrupted run.
TEST_CASE("a stopped mgrl train keeps what finished and resumes the rest", "[cli][data]") {
  Sandbox box("stop");
  const fs::path out = box.path("bundle");
  const std::string settings = kFast + " --set behaviors.hit.learner.checkpoint_every=100000";
  const Run stopped = box.train(settings + " --out " + shellWord(out), "MGRL_STOP_AFTER_CHECKPOINTS=1");
  INFO("stderr: " << stopped.err);
  CHECK(stopped.status == 130);
  CHECK(stopped.out.empty());
  CHECK_THAT(stopped.lastErrorLine(), StartsWith("mgrl: interrupted while training hit (checkpoint at ") &&
                                          Contains("kept approach in " + out.string()) && Contains("--resume`"));
  requireFile(out / "approach.q.npy");
  CHECK_FALSE(fs::exists(out / "hit.q.npy"));
  requireFile(box.path("bundle.checkpoints") / "hit" / "state.json");
  requireRefusal(box.eval(settings + " --trials 3 --policy " + shellWord(out)),
                 "expected a trained table for behaviour 'hit', found none: its training was interrupted; run mgrl "
                 "train");

  const Run resumed = box.train(settings + " --resume --out " + shellWord(out));
  const json report = resumed.report();
  CHECK_THAT(resumed.err, Contains("resume: approach: already trained in " + out.string() + ", kept"));
  CHECK_THAT(resumed.err, Contains("resume: hit: continuing from the checkpoint at "));
  CHECK(report["behaviors"]["hit"]["stats"]["resumed"] == true);
  CHECK_FALSE(report["behaviors"].contains("approach"));
  CHECK(box.eval(settings + " --trials 3 --policy " + shellWord(out)).status == 0);

  const fs::path straight = box.path("straight");
  REQUIRE(box.train(settings + " --out " + shellWord(straight)).status == 0);
  CHECK(readText(out / "approach.q.npy") == readText(straight / "approach.q.npy"));
  CHECK(readText(out / "hit.q.npy") == readText(straight / "hit.q.npy"));
  CHECK_FALSE(fs::exists(box.path("bundle.checkpoints")));
}

// The real signal: Ctrl-C once training has started.
TEST_CASE("SIGINT during mgrl train exits 130 with a checkpoint and the resume command", "[cli][data]") {
  Sandbox box("sigint");
  const fs::path out = box.path("bundle"), err = box.path("err.txt");
  const std::string command =
      mgrl::test::shellWord(MGRL_BINARY) + " train " + shellWord(kBoxing) + box.where() +
      " --set behaviors.approach.learner.budget=200000 --set behaviors.hit.learner.budget=1000000000 --out " +
      shellWord(out);
  // Start, wait until hit is training, press Ctrl-C, report the exit code.
  const std::string script = command + " 2>" + shellWord(err) + " >/dev/null & pid=$!; for i in $(seq 600); do grep -q 'train hit:' " +
                             shellWord(err) + " && break; sleep 0.1; done; sleep 0.3; kill -INT $pid; wait $pid; echo $? > " +
                             shellWord(box.path("status"));
  const fs::path file = box.path("sigint.sh");
  std::ofstream(file) << script << "\n";
  REQUIRE(std::system(("bash " + shellWord(file)).c_str()) == 0);
  const std::string status = readText(box.path("status"));
  const std::string stderrText = readText(err);
  INFO("stderr: " << stderrText);
  CHECK(status == "130\n");
  CHECK_THAT(stderrText, Contains("mgrl: interrupted while training hit (checkpoint at ") &&
                             Contains("kept approach in " + out.string()));
  requireFile(out / "approach.q.npy");
  requireFile(box.path("bundle.checkpoints") / "hit" / "state.json");
}

// The default bundle depends on everything that trained it, so training another
// learner does not overwrite the first; eval with the same --set finds each.
TEST_CASE("another learner trains into another default bundle", "[cli][data]") {
  Sandbox box("paths");
  const std::string vi =
      "--set behaviors.hit.learner.budget=400000 --set behaviors.approach.learner.type=value_iteration";
  const json q = box.train(kFast + " --behavior approach").report();
  const json v = box.train(vi + " --behavior approach").report();
  CHECK(q["policy"] != v["policy"]);
  CHECK(fs::path(q["policy"].get<std::string>()).parent_path() == box.cache() / "policies");
  CHECK(json::parse(readText(fs::path(v["policy"].get<std::string>()) / "manifest.json"))["behaviors"]["approach"]
            ["record"]["learner"] == "value_iteration");
  CHECK(json::parse(readText(fs::path(q["policy"].get<std::string>()) / "manifest.json"))["behaviors"]["approach"]
            ["record"]["learner"] == "q_learning");

  // A bundle trained with another learner, given with --policy, is used with its settings.
  const fs::path out = box.path("vi");
  REQUIRE(box.train(vi + " --out " + shellWord(out)).status == 0);
  const Run eval = box.eval(kFast + " --trials 3 --policy " + shellWord(out));
  INFO("stderr: " << eval.err);
  CHECK(eval.status == 0);
  CHECK_THAT(eval.err, Contains("using the settings the bundle was trained with (approach.learner.type=value_iteration)"));
}

// Sizes are checked before anything is allocated or trained: a grid too large
// to exist, and a behaviour whose training would need more memory than --max-memory.
TEST_CASE("mgrl train refuses a grid or a problem too large before training anything", "[cli][data]") {
  Sandbox box("toolarge");
  const fs::path out = box.path("bundle");
  requireRefusal(box.train(kFast + " --set behaviors.hit.discretizer.angles=300 --set "
                                   "behaviors.hit.discretizer.distances=300 --set behaviors.hit.discretizer.heights=300 "
                                   "--out " + shellWord(out)),
                 "cylindrical3d: expected a grid of at most 20000000 vertices, found 27000000 (300 angle x 300 "
                 "distance x 300 height)");
  CHECK_FALSE(fs::exists(out));
  // Not even the compact model fits in 30 MB.
  const Run refused = box.train(kFast + " --max-memory 0.03 --out " + shellWord(out));
  requireRefusal(refused, "behaviors.hit: training on a cylindrical3d grid of 1920 vertices x ");
  CHECK_THAT(refused.lastErrorLine(), Contains("(compact model and Q tables); expected at most 30.0 MB (--max-memory)"));
  CHECK_THAT(refused.err, !Contains("train approach:"));  // nothing was trained first
  CHECK_FALSE(fs::exists(out));
  requireOneLineRefusal(box.train(kFast + " --max-memory 0"), "--max-memory: expected gigabytes in (0, 1000000], found 0");
}

// A refining learner's tables grow to its budget, and with `starts` every start's table is
// held until one is kept: --max-memory counts both before training anything.
TEST_CASE("mgrl train counts adaptive_value_iteration's vertex budget and starts against --max-memory",
          "[cli][data][adaptive]") {
  Sandbox box("adaptive-memory");
  const std::string adaptive =
      "--set behaviors.approach.learner.budget=200000 --set behaviors.hit.discretizer.type=kd_tree "
      "--set behaviors.hit.discretizer.bounds=hits "
              "--set behaviors.hit.learner.type=adaptive_value_iteration --set behaviors.hit.learner.max_vertices=1920";
  // The initial tree has 75 vertices (4 x 4 x 2 cells); the last round's 1920 x 1438
  // actions need about 88 MB tabulated.
  const Run budget = box.train(adaptive + " --max-memory 0.05 --out " + shellWord(box.path("a")));
  requireRefusal(budget, "behaviors.hit: training on a kd_tree grid of up to 1920 vertices x ");
  CHECK_THAT(budget.lastErrorLine(), Contains("(tabulated model and Q tables); expected at most 50.0 MB"));
  CHECK_THAT(budget.err, !Contains("train approach:"));
  // Three starts hold two more tables of 1920 x 1438 floats (22 MB): over 100 MB.
  const Run starts = box.train(adaptive + " --set behaviors.hit.learner.starts=3 --max-memory 0.1 --out " +
                               shellWord(box.path("b")));
  requireRefusal(starts, "behaviors.hit: training on a kd_tree grid of up to 1920 vertices x ");
  CHECK_THAT(starts.lastErrorLine(), Contains("(tabulated model and Q tables, 2 more tables held); expected at most "
                                              "100.0 MB"));
  CHECK_FALSE(fs::exists(box.path("a")));
  CHECK_FALSE(fs::exists(box.path("b")));
}

// When the tabulated problem does not fit in --max-memory, train falls back to
// the compact model (rewards only), which gives the same tables; --model chooses.
TEST_CASE("mgrl train trains on the compact model when the tabulated one does not fit", "[cli][data][compact]") {
  Sandbox box("compact");
  const fs::path tabulated = box.path("tabulated"), compact = box.path("compact"), forced = box.path("forced");
  REQUIRE(box.train(kFast + " --out " + shellWord(tabulated)).status == 0);
  // boxing's hit problem: about 88 MB tabulated, 44 MB compact.
  const Run fallback = box.train(kFast + " --max-memory 0.05 --out " + shellWord(compact));
  INFO("stderr: " << fallback.err);
  REQUIRE(fallback.status == 0);
  const json report = fallback.report();
  CHECK(report["behaviors"]["hit"]["model"] == "compact");
  CHECK(report["behaviors"]["approach"]["model"] == "tabulated");
  // The compact model is about the size of the hit Q table (11 MB), not five times it.
  CHECK(report["behaviors"]["hit"]["model_bytes"].get<double>() < 1.3 * report["behaviors"]["hit"]["table_bytes"].get<double>());
  CHECK_THAT(fallback.err, Contains("train hit: the tabulated model and tables would need about") &&
                               Contains("over --max-memory 50.0 MB: using the compact model"));
  CHECK_THAT(fallback.err, Contains("rewards (compact model) tabulated"));
  CHECK_THAT(fallback.err, !Contains("train approach: the tabulated model"));  // approach fits
  CHECK(readText(tabulated / "hit.q.npy") == readText(compact / "hit.q.npy"));
  REQUIRE(box.train(kFast + " --behavior approach --model compact --out " + shellWord(forced)).status == 0);
  CHECK(readText(tabulated / "approach.q.npy") == readText(forced / "approach.q.npy"));

  const Run refused = box.train(kFast + " --model tabulated --max-memory 0.05 --out " + shellWord(box.path("no")));
  requireRefusal(refused, "behaviors.hit: training on a cylindrical3d grid of 1920 vertices x ");
  CHECK_THAT(refused.lastErrorLine(), Contains("(tabulated model and Q tables); expected at most 50.0 MB "
                                               "(--max-memory): use a coarser grid, --model compact (about 44."));
  requireOneLineRefusal(box.train(kFast + " --model cheap"), "--model: expected auto, tabulated or compact, found 'cheap'");
  requireRefusal(box.train("--behavior approach --model compact --set behaviors.approach.learner.type=adaptive_value_iteration "
                           "--set behaviors.approach.discretizer.type=kd_tree"),
                 "behaviors.approach: --model compact: expected a learner that takes a compact model (q_learning, "
                 "value_iteration), found adaptive_value_iteration");
}

// An --out folder that cannot take files is refused before training, not after.
// /proc takes no new files, even from root (CI runs as root, where permissions would not
// stop the write).
TEST_CASE("mgrl train refuses an unwritable --out folder before training", "[cli][data]") {
  Sandbox box("readonly");
  const fs::path out = "/proc/mgrl_test_bundle";
  const Run r = box.train(kFast + " --out " + shellWord(out));
  requireRefusal(r, "--out " + out.string() + ": expected a folder where files can be written, found /proc is not "
                    "writable");
  CHECK_THAT(r.err, !Contains("train approach:"));
}

// Through the binary: a checkpoint whose state the learner rejects
// (here a state index out of range, with the seal recomputed so that only the learner's
// own check can catch it) is reported, naming state.json, and ignored; the run trains
// from the start and ends with the table of a clean run.
TEST_CASE("mgrl train --resume ignores a checkpoint whose learner state is out of range", "[cli][data]") {
  Sandbox box("badstate");
  const fs::path out = box.path("bundle"), state = box.path("bundle.checkpoints") / "approach" / "state.json";
  REQUIRE(box.train(kCheckpointed + " --out " + shellWord(out), "MGRL_EXIT_AFTER_CHECKPOINTS=1").status == 75);
  json checkpoint = json::parse(readText(state));
  checkpoint["state"]["walk"]["state"] = 99999;
  checkpoint["hash"] = mgrl::manifestHash(checkpoint);
  std::ofstream(state) << checkpoint.dump(2);

  const Run resumed = box.train(kCheckpointed + " --resume --out " + shellWord(out));
  INFO("stderr: " << resumed.err);
  const json report = resumed.report();
  CHECK(report["behaviors"]["approach"]["stats"]["resumed"] == false);
  CHECK_THAT(resumed.err, Contains(state.string()) && Contains("ignoring the checkpoint") &&
                              Contains("resume: approach: no checkpoint to continue from, trained from the start"));
  CHECK_THAT(resumed.err, !Contains("continuing from the checkpoint"));
  const fs::path straight = box.path("straight");
  REQUIRE(box.train(kCheckpointed + " --out " + shellWord(straight)).status == 0);
  CHECK(readText(out / "approach.q.npy") == readText(straight / "approach.q.npy"));
}

}  // namespace cli_learn_test
