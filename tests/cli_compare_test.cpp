// `mgrl compare` through the real binary: its numbers are those of separate
// `mgrl train` + `mgrl eval` runs with the same settings, a second run reuses the first's
// bundles, the report folder holds the plots and tables, and mistakes are refused in one
// line before anything is trained.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.hpp"
#include "compare_command.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/npy.hpp"
#include "mgrl/reports/compare_report.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_compare_test {

namespace fs = std::filesystem;
using Catch::Contains;
using nlohmann::json;
using mgrl::test::readText;
using mgrl::test::Run;
using mgrl::test::shellWord;

namespace {

const std::string kBoxing = std::string(MGRL_SOURCE_DIR) + "/scenarios/boxing.yaml";
// The shared approach behaviour trained in a fraction of a second.
// The hit grid coarser than the scenario's (10 x 16 x 3 vertices, a quarter), so that value
// iteration, compare's reference in every run, takes seconds, under the sanitizers too.
const std::string kFastApproach =
    "--set behaviors.approach.learner.budget=200000 --set behaviors.hit.discretizer.angles=10 "
    "--set behaviors.hit.discretizer.heights=3";
const std::string kCompare = "compare " + shellWord(kBoxing) + " --behavior hit --learners q_learning,value_iteration " +
                             "--learner-set q_learning:budget=300000 --trials 20 " + kFastApproach;

struct Sandbox : mgrl::test::CliSandbox {
  Sandbox() : CliSandbox("mgrl_cli_compare") {}
  Run run(const std::string& arguments) { return mgrl::test::runMgrl(arguments + where(), dir()); }
};

TEST_CASE("mgrl compare reports what separate train and eval runs measure, and reuses its bundles", "[cli][data][slow]") {
  Sandbox box;
  const Run compared = box.run(kCompare + " --seeds 1,2 --json --report " + shellWord(box.path("report")));
  const json report = compared.report();
  REQUIRE(report["runs"].size() == 3);  // q_learning x 2 seeds, value_iteration once (it has no seed)
  const json& q1 = report["runs"][0];
  CHECK(q1["learner"] == "q_learning");
  CHECK(q1["seed"] == 1);
  CHECK(report["runs"][2]["learner"] == "value_iteration");
  CHECK(report["runs"][2]["value_rmse"] == 0.0);  // value iteration is the reference
  CHECK(report["runs"][2]["greedy_agreement"] == 1.0);
  CHECK(q1["value_rmse"].get<double>() > 0);
  CHECK(q1["updates"] == 300000);

  // The same run by hand: train with the same settings, evaluate on the same trials.
  const std::string sets = kFastApproach + " --set behaviors.hit.learner.budget=300000 --set behaviors.hit.learner.seed=1";
  const Run trained = box.run("train " + shellWord(kBoxing) + " --json --out " + shellWord(box.path("by-hand")) + " " + sets);
  REQUIRE(trained.status == 0);
  const json evaluated = box.run("eval " + shellWord(kBoxing) + " --json --trials 20 --seed 1 --policy " +
                                 shellWord(box.path("by-hand")) + " " + sets)
                             .report();
  // The same table, byte for byte: compare trains as `mgrl train` does.
  auto hitTableHash = [](const fs::path& bundle) {
    return json::parse(readText(bundle / "manifest.json"))["behaviors"]["hit"]["table"]["hash"];
  };
  CHECK(hitTableHash(q1["policy"].get<std::string>()) == hitTableHash(box.path("by-hand")));
  CHECK(hitTableHash(report["runs"][1]["policy"].get<std::string>()) != hitTableHash(box.path("by-hand")));  // seed 2
  CHECK(q1["success_rate"] == evaluated["success_rate"]);
  CHECK(q1["mean_time_to_hit_s"] == evaluated["mean_time_to_hit_s"]);
  CHECK(q1["mean_return"] == evaluated["mean_return"]);
  const json means = report["learners"]["q_learning"]["mean"];
  CHECK(means["updates"] == 300000.0);
  CHECK(means["success_rate"].get<double>() ==
        Approx((q1["success_rate"].get<double>() + report["runs"][1]["success_rate"].get<double>()) / 2));

  // Learning curves: 10 snapshots per run (the default), each evaluated on the first 20 of
  // the same starts (the default 50, capped by --trials 20); q_learning's at budget * i / 10.
  CHECK(report["snapshots"] == 10);
  CHECK(report["snapshot_trials"] == 20);
  for (const json& run : report["runs"]) {
    INFO(run["learner"].dump() + " seed " + run["seed"].dump());
    REQUIRE(run["snapshots"].is_object());
    const json& points = run["snapshots"]["points"];
    REQUIRE(points.size() >= 3);
    for (const json& p : points) {
      CHECK(p[3].get<double>() >= 0);
      CHECK(p[3].get<double>() <= 1);
    }
    // The last snapshot is of the final table, on the same 20 trials as the final evaluation.
    CHECK(points.back()[0] == run["updates"]);
    CHECK(points.back()[3] == run["success_rate"]);
    CHECK(points.back()[5] == run["mean_return"]);
    if (run["learner"] == "q_learning") {
      REQUIRE(points.size() == 10);
      for (std::size_t i = 0; i < 10; ++i) CHECK(points[i][0] == 300000 * (i + 1) / 10);
    }
  }
  CHECK(report["learners"]["q_learning"]["success_curve"].size() == 10);


  // The report: the tables and a plot per metric, nothing fetched from the network.
  const std::string html = readText(box.path("report") / "index.html");
  CHECK(html.find("<svg") != std::string::npos);
  CHECK(html.find("Bellman residual against updates") != std::string::npos);
  CHECK(html.find("Bellman residual against training seconds") != std::string::npos);
  CHECK(html.find("Success rate against updates") != std::string::npos);
  CHECK(html.find("Success rate against training seconds") != std::string::npos);
  const std::string curves = readText(box.path("report") / "curves.csv");
  CHECK(curves.find("q_learning,2,snapshot,300000,") != std::string::npos);
  CHECK(curves.find("q_learning,1,training,") != std::string::npos);
  // Numbers for people: the table size in MB, updates with a prefix, no exponent anywhere.
  CHECK(html.find("e+") == std::string::npos);
  CHECK(html.find(" MB<br><span class=\"sd\">&plusmn; ") != std::string::npos);
  CHECK(html.find(" M<br><span class=\"sd\">&plusmn; ") != std::string::npos);
  CHECK(html.find(" s<br><span class=\"sd\">&plusmn; ") != std::string::npos);
  CHECK(html.find("src=") == std::string::npos);  // self-contained: it opens from disk, offline
  CHECK(html.find("href=\"http") == std::string::npos);
  CHECK(readText(box.path("report") / "results.csv").find("q_learning,2,") != std::string::npos);
  CHECK(json::parse(readText(box.path("report") / "results.json"))["runs"].size() == 3);

  // A second run reuses every bundle: nothing is trained again.
  const Run again = box.run(kCompare + " --seeds 1 --json");
  REQUIRE(again.status == 0);
  CHECK(again.err.find("train hit:") == std::string::npos);
  CHECK(again.report()["runs"][0]["success_rate"] == q1["success_rate"]);
  CHECK(again.report()["runs"][0]["snapshots"] == q1["snapshots"]);  // kept in the cached bundle
  CHECK(again.err.find("success % along training") != std::string::npos);
}

// A bundle cached before snapshots were recorded (or with other snapshot settings) still
// loads; when snapshots are asked for, its run is trained again to take them: the same table.
TEST_CASE("mgrl compare reuses bundles cached without snapshots and retrains them when curves are asked for",
          "[cli][data]") {
  Sandbox box;
  const std::string compare = "compare " + shellWord(kBoxing) + " --behavior hit --learners q_learning " +
                              "--learner-set q_learning:budget=200000 --trials 10 --json " + kFastApproach;
  const json first = box.run(compare + " --snapshots 4").report();
  REQUIRE(first["runs"][0]["snapshots"]["points"].size() == 4);
  // Make it an old entry: no "snapshots" in its record.
  const fs::path manifest = fs::path(first["runs"][0]["policy"].get<std::string>()) / "manifest.json";
  json m = json::parse(readText(manifest));
  REQUIRE(m["behaviors"]["hit"]["record"].erase("snapshots") == 1);
  m["hash"] = mgrl::manifestHash(m);  // sealed again: an old entry, not a tampered one
  std::ofstream(manifest) << m.dump(2);

  const Run without = box.run(compare + " --snapshots 0");
  REQUIRE(without.status == 0);
  CHECK(without.err.find("train hit:") == std::string::npos);  // loaded, not trained
  CHECK(without.report()["runs"][0]["snapshots"].is_null());
  CHECK(without.report()["runs"][0]["value_rmse"] == first["runs"][0]["value_rmse"]);

  const Run with = box.run(compare + " --snapshots 4");
  REQUIRE(with.status == 0);
  CHECK(with.err.find("no snapshots taken with these settings; training again") != std::string::npos);
  const json withReport = with.report();
  const json& again = withReport["runs"][0]["snapshots"]["points"];
  REQUIRE(again.size() == 4);
  for (std::size_t i = 0; i < 4; ++i) {  // the same tables on the same trials (the seconds differ)
    CHECK(again[i][0] == first["runs"][0]["snapshots"]["points"][i][0]);
    CHECK(again[i][3] == first["runs"][0]["snapshots"]["points"][i][3]);
  }
  CHECK(withReport["runs"][0]["value_rmse"] == first["runs"][0]["value_rmse"]);  // the same table
  // Other snapshot settings: trained again too.
  const Run other = box.run(compare + " --snapshots 4 --snapshot-trials 5");
  REQUIRE(other.status == 0);
  CHECK(other.err.find("training again") != std::string::npos);
  CHECK(other.report()["snapshot_trials"] == 5);
}

// Value iteration alone: one deterministic run, which is also the reference's bundle.
const std::string kCompareValueIteration = "compare " + shellWord(kBoxing) +
                                           " --behavior hit --learners value_iteration --trials 5 --snapshots 0 " +
                                           kFastApproach;

// The row of `learner` in compareText()'s table, or "" if there is none.
std::string textRow(const std::string& text, const std::string& learner) {
  for (const std::string& line : mgrl::test::lines(text))
    if (line.rfind(learner + " ", 0) == 0) return line;
  return "";
}

std::size_t countOf(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

// Audit finding: compare called the share of non-zero Q entries the share "touched" / "ever
// updated", and value iteration, which updates every entry on every sweep, showed 77.7 %.
TEST_CASE("mgrl compare reports the share of non-zero Q entries under that name, not as entries updated",
          "[cli][data]") {
  Sandbox box;
  const Run compared = box.run(kCompareValueIteration + " --json --report " + shellWord(box.path("report")));
  const json report = compared.report();
  REQUIRE(report["runs"].size() == 1);
  const json& run = report["runs"][0];
  CHECK_FALSE(run.contains("touched_share"));
  REQUIRE(run.contains("nonzero_share"));
  // It is what the name says: the share of the saved table's entries that are not zero.
  const std::string bytes = readText(fs::path(run["policy"].get<std::string>()) / "hit.q.npy");
  const std::vector<float> q = mgrl::npyDecode<float>(bytes, "hit.q.npy");
  const auto nonzero = std::count_if(q.begin(), q.end(), [](float x) { return x != 0.0f; });
  CHECK(run["nonzero_share"].get<double>() == Approx(static_cast<double>(nonzero) / static_cast<double>(q.size())));
  // Value iteration backs up every entry on every sweep (its updates are a whole number of
  // sweeps over them), and still has zeros: this figure is no count of updates.
  CHECK(run["updates"].get<std::uint64_t>() % q.size() == 0);
  CHECK(run["nonzero_share"].get<double>() < 1.0);
  const std::string text = mgrl::app::compareText(report);
  CAPTURE(text);
  CHECK_THAT(text, Contains("non-zero %"));
  CHECK_THAT(text, !Contains("touched") && !Contains("updated"));
  const std::string html = readText(box.path("report") / "index.html");
  CHECK_THAT(html, Contains("Q entries non-zero"));
  CHECK_THAT(html, !Contains("touched"));
  CHECK_THAT(mgrl::test::lines(readText(box.path("report") / "results.csv")).front(), Contains(",nonzero_share,"));
}

// Audit finding: figures a cached bundle's record lacks (written before they were recorded)
// were reported as a measured 0 s of training, 0 updates and a residual of 0.
TEST_CASE("mgrl compare reports training figures missing from a cached bundle as missing, not as 0",
          "[cli][data]") {
  Sandbox box;
  const json first = box.run(kCompareValueIteration + " --json").report();
  REQUIRE(first["runs"][0]["train_seconds"].get<double>() > 0);
  // Make it an older bundle: a record without the training time, updates and residual.
  const fs::path manifest = fs::path(first["runs"][0]["policy"].get<std::string>()) / "manifest.json";
  json m = json::parse(readText(manifest));
  json& record = m["behaviors"]["hit"]["record"];
  for (const char* key : {"seconds", "updates", "final_residual"}) REQUIRE(record.erase(key) == 1);
  if (m.contains("hash")) m["hash"] = mgrl::manifestHash(m);  // sealed again: an old entry, not a tampered one
  std::ofstream(manifest) << m.dump(2);

  const Run again = box.run(kCompareValueIteration + " --json --report " + shellWord(box.path("report")));
  CHECK(again.err.find("train hit:") == std::string::npos);  // loaded, not trained again
  const json report = again.report();
  const json& run = report["runs"][0];
  CHECK(run["train_seconds"].is_null());
  CHECK(run["updates"].is_null());
  CHECK(run["final_residual"].is_null());
  CHECK(report["reference"]["train_seconds"].is_null());
  CHECK(report["learners"]["value_iteration"]["mean"]["train_seconds"].is_null());
  CHECK(report["learners"]["value_iteration"]["mean"]["updates"].is_null());
  CHECK(run["success_rate"] == first["runs"][0]["success_rate"]);  // what was measured still is

  // Text: "n/a" in the train s and updates columns.
  const std::string row = textRow(mgrl::app::compareText(report), "value_iteration");
  CAPTURE(row);
  CHECK(countOf(row, "n/a") == 2);
  // CSV: empty fields, as for any missing value; HTML: n/a.
  const std::vector<std::string> csv = mgrl::test::lines(readText(box.path("report") / "results.csv"));
  REQUIRE(csv.size() >= 2);
  CAPTURE(csv[0], csv[1]);
  auto field = [](const std::string& line, std::size_t index) {
    std::size_t begin = 0;
    for (std::size_t i = 0; i < index; ++i) begin = line.find(',', begin) + 1;
    return line.substr(begin, line.find(',', begin) - begin);
  };
  const std::vector<std::string> header = {"learner", "seed", "success_rate", "mean_time_to_hit_s", "mean_return",
                                           "train_seconds", "updates"};
  for (std::size_t i = 0; i < header.size(); ++i) REQUIRE(field(csv[0], i) == header[i]);
  CHECK(field(csv[1], 5).empty());
  CHECK(field(csv[1], 6).empty());
  CHECK_FALSE(field(csv[1], 2).empty());
  const std::string html = readText(box.path("report") / "index.html");
  const std::size_t rowAt = html.find("<tr><td>value_iteration</td>");
  REQUIRE(rowAt != std::string::npos);
  const std::string htmlRow = html.substr(rowAt, html.find("</tr>", rowAt) - rowAt);
  CAPTURE(htmlRow);
  std::vector<std::string> cells;  // the learner, then the metrics in results.csv's order
  for (std::size_t at = htmlRow.find("<td>"); at != std::string::npos; at = htmlRow.find("<td>", at + 4))
    cells.push_back(htmlRow.substr(at + 4, htmlRow.find("</td>", at) - at - 4));
  REQUIRE(cells.size() >= 6);
  CHECK(cells[4] == "n/a");  // train_seconds
  CHECK(cells[5] == "n/a");  // updates
  CHECK(cells[1] != "n/a");  // success_rate, measured
}

// --reference-set: value iteration on a finer grid, read at each table's vertices.
TEST_CASE("mgrl compare measures tables against value iteration on a finer grid", "[cli][data][slow]") {
  Sandbox box;
  const std::string compare = "compare " + shellWord(kBoxing) +
                              " --behavior hit --learners value_iteration --trials 10 --snapshots 3 --json " +
                              kFastApproach;  // on the 10 x 16 x 3 hit grid
  // The behaviour's grid given explicitly is the same grid: vertex by vertex, no difference.
  const json same = box.run(compare + " --reference-set angles=10").report();
  CHECK(same["runs"][0]["value_rmse"] == 0.0);
  CHECK(same["runs"][0]["greedy_agreement"] == 1.0);
  CHECK(same["runs"][0]["reference_interpolated"] == false);
  // A finer grid (the coarse angles and heights halved): interpolated at the coarse vertices.
  const json finer =
      box.run(compare + " --reference-set angles=19 --reference-set heights=5").report();
  const json& reference = finer["reference"];
  CHECK(reference["vertices"] == 19 * 16 * 5);
  CHECK_THAT(reference["description"].get<std::string>(), Contains("interpolated at each table's vertices"));
  const json& run = finer["runs"][0];
  CHECK(run["reference_interpolated"] == true);
  CHECK(run["value_rmse"].get<double>() > 0);  // the coarse grid's values are not the fine grid's
  CHECK(run["value_rmse"].get<double>() < 0.5);
  CHECK(run["greedy_agreement"].get<double>() > 0.3);
  CHECK(run["greedy_agreement"].get<double>() < 1.0);
}

// `mgrl compare` checks --report by writing `.mgrl-probe-PID` there and removing it; a
// compare killed in between left the probe for good. The next run removes those of
// processes that are gone (a live one may be comparing now), as train does beside --out.
TEST_CASE("mgrl compare removes the writability probe a killed run left in --report", "[cli][data]") {
  Sandbox box;
  const fs::path report = box.path("report");
  fs::create_directories(report);
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  int status = 0;
  ::waitpid(gone, &status, 0);
  const fs::path dead = report / (".mgrl-probe-" + std::to_string(gone));
  const fs::path live = report / (".mgrl-probe-" + std::to_string(::getpid()));
  for (const fs::path& p : {dead, live}) std::ofstream(p) << "x";

  REQUIRE(box.run(kCompare + " --seeds 1 --report " + shellWord(report)).status == 0);
  CHECK_FALSE(fs::exists(dead));
  CHECK(fs::exists(live));
}

// The snapshots were evaluated with targets at the hitting points' centroid
// height while the final evaluation (eval's) put them at the scenario's world.target_height:
// on kick.yaml (0.6 m) the last snapshot, the trained table itself, said 40 % and the
// final evaluation 55 %. Both now take the session's task.
TEST_CASE("mgrl compare's last snapshot is its final evaluation, at the scenario's target height",
          "[cli][data][slow]") {
  Sandbox box;
  const std::string kick = std::string(MGRL_SOURCE_DIR) + "/scenarios/kick.yaml";
  const json report = box.run("compare " + shellWord(kick) +
                              " --behavior kick --learners q_learning --learner-set q_learning:budget=300000 "
                              "--trials 20 --snapshots 2 --json")
                          .report();
  const json& run = report["runs"][0];
  const json& last = run["snapshots"]["points"].back();
  REQUIRE(last[0] == run["updates"]);  // taken at the end of training: the table evaluated
  CHECK(last[3] == run["success_rate"]);
  CHECK(last[4] == run["mean_time_to_hit_s"]);
  CHECK(last[5] == run["mean_return"]);
}

TEST_CASE("mgrl compare refuses mistakes in one line before training anything", "[cli][data]") {
  Sandbox box;
  const std::string base = "compare " + shellWord(kBoxing) + " --behavior hit ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {base + "--learners q_learning,sarsa", "--learners: expected registered learners (q_learning, value_iteration"},
      {base + "--learners q_learning,q_learning", "--learners: expected each learner once, found 'q_learning' twice"},
      {base + "--learners q_learning --seeds 1,1", "--seeds: expected each seed once"},
      {base + "--learners q_learning --seeds 1,x", "--seeds: expected whole numbers >= 0 separated by commas, found 'x'"},
      {base + "--learners q_learning --learner-set budget=5", "--learner-set: expected LEARNER:KEY=VALUE"},
      {base + "--learners q_learning --learner-set value_iteration:sweeps=5",
       "--learner-set value_iteration:sweeps=5: expected a learner from --learners (q_learning)"},
      {base + "--learners q_learning --learner-set q_learning:budget=-5", "--learners q_learning: "},
      {"compare " + shellWord(kBoxing) + " --behavior kick --learners q_learning",
       "--behavior: expected one of the scenario's behaviours (approach, hit), found 'kick'"},
      {base + "--learners q_learning --report /proc/mgrl-report", "--report /proc/mgrl-report: expected a folder"},
      {base + "--learners q_learning --snapshots 5000", "--snapshots: expected a number of snapshots per run in [0, 1000], found 5000"},
      {base + "--learners q_learning --trials 20 --snapshot-trials 30",
       "--snapshot-trials: expected at most --trials (20): snapshots are evaluated on the first of the same trial "
       "starts, found 30"},
      {base + "--learners q_learning --snapshot-trials 0", "--snapshot-trials: expected a number of trials of at least 1, found 0"},
      {base + "--learners q_learning --reference-set angles",
       "--reference-set: expected KEY=VALUE, KEY a parameter of behaviors.hit.discretizer (e.g. angles=40), found 'angles'"},
      {base + "--learners q_learning --reference-set learner.tolerance=1e-6",
       "--reference-set: expected KEY=VALUE, KEY a parameter of behaviors.hit.discretizer (e.g. angles=40), found "
       "'learner.tolerance=1e-6'"},
      {base + "--learners q_learning --reference-set anglez=40", "--reference-set: "},
      {base + "--learners q_learning --reference-set angles=1", "--reference-set: "},
      // A reference that does not cover the behaviour's grid (checked once the graph is loaded).
      {base + "--learners q_learning --reference-set bounds=given --reference-set angle_min=-10 "
              "--reference-set angle_max=10",
       "--reference-set: expected a reference grid that covers behaviors.hit's grid, found its vertex 0 at angle"},
      // A learner that does not fit the behaviour's grid (checked once the graph is loaded).
      {base + "--learners q_learning,adaptive_value_iteration",
       "--learners adaptive_value_iteration: behaviors.hit: adaptive_value_iteration: expected a discretizer that can "
       "be refined (type kd_tree), found cylindrical3d"},
  };
  for (const auto& [arguments, message] : cases) {
    INFO(arguments);
    const Run refused = box.run(arguments);
    CHECK(refused.status == 1);
    CHECK(refused.out.empty());
    CHECK_THAT(refused.lastErrorLine(), Contains(message));
    CHECK(refused.err.find("train ") == std::string::npos);
  }
  CHECK_FALSE(fs::exists(box.cache() / "compare"));
  // mgrl train refuses the same before training the other behaviour.
  const Run train = box.run("train " + shellWord(kBoxing) + " --set behaviors.hit.learner.type=adaptive_value_iteration");
  CHECK(train.status == 1);
  CHECK_THAT(train.lastErrorLine(), Contains("behaviors.hit: adaptive_value_iteration: expected a discretizer that can be "
                                             "refined (type kd_tree), found cylindrical3d"));
  CHECK(train.err.find("train approach") == std::string::npos);
}

}  // namespace

TEST_CASE("the compare report writes numbers for people: units, prefixes, three digits, no exponent", "[compare]") {
  using mgrl::reportNumber;
  CHECK(reportNumber("table_bytes", 1.104e7) == "11.0 MB");
  CHECK(reportNumber("table_bytes", 512) == "512 B");
  CHECK(reportNumber("table_bytes", 2.5e9) == "2.50 GB");
  CHECK(reportNumber("updates", 6.626e7) == "66.3 M");
  CHECK(reportNumber("updates", 300000) == "300 k");
  CHECK(reportNumber("updates", 42) == "42");
  CHECK(reportNumber("updates", 999999) == "1.00 M");
  CHECK(reportNumber("train_seconds", 3.6789) == "3.68 s");
  CHECK(reportNumber("train_seconds", 123.4) == "123 s");
  CHECK(reportNumber("train_seconds", 0.0123) == "12.3 ms");
  CHECK(reportNumber("mean_time_to_hit_s", 0) == "0 s");
  CHECK(reportNumber("mean_time_to_hit_s", 0.0613, true) == "0.0613 s");  // a spread in its mean's unit
  CHECK(reportNumber("decision_us", 12.34) == "12.3 us");
  CHECK(reportNumber("decision_us", 2500) == "2.50 ms");
  CHECK(reportNumber("success_rate", 0.95) == "95.0 %");
  CHECK(reportNumber("success_rate", 0.021, true) == "2.1");  // a spread, in percentage points
  CHECK(reportNumber("mean_return", 0.012345) == "0.0123");
  CHECK(reportNumber("mean_return", 1234.5) == "1234");
  CHECK(reportNumber("value_rmse", 2.5e-5) == "2.50e-05");
  CHECK(reportNumber("value_rmse", -0.5) == "-0.500");
}

}  // namespace cli_compare_test
