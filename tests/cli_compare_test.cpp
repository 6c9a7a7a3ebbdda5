// `mgrl compare` through the real binary (issue 15): its numbers are those of separate
// `mgrl train` + `mgrl eval` runs with the same settings, a second run reuses the first's
// bundles, the report folder holds the plots and tables, and mistakes are refused in one
// line before anything is trained.
#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Contains;
using nlohmann::json;
using mgrl::test::readText;
using mgrl::test::Run;
using mgrl::test::shellWord;

namespace {

const std::string kBoxing = std::string(MGRL_SOURCE_DIR) + "/scenarios/boxing.yaml";
// The shared approach behaviour trained in a fraction of a second.
const std::string kFastApproach = "--set behaviors.approach.learner.budget=200000";
const std::string kCompare = "compare " + shellWord(kBoxing) + " --behavior hit --learners q_learning,value_iteration " +
                             "--learner-set q_learning:budget=300000 --trials 20 " + kFastApproach;

struct Sandbox : mgrl::test::CliSandbox {
  Sandbox() : CliSandbox("mgrl_cli_compare") {}
  Run run(const std::string& arguments) { return mgrl::test::runMgrl(arguments + where(), dir()); }
};

TEST_CASE("mgrl compare reports what separate train and eval runs measure, and reuses its bundles", "[cli][data]") {
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
  CHECK(q1["success_rate"] == evaluated["success_rate"]);
  CHECK(q1["mean_time_to_hit_s"] == evaluated["mean_time_to_hit_s"]);
  CHECK(q1["mean_return"] == evaluated["mean_return"]);
  const json means = report["learners"]["q_learning"]["mean"];
  CHECK(means["updates"] == 300000.0);
  CHECK(means["success_rate"].get<double>() ==
        Approx((q1["success_rate"].get<double>() + report["runs"][1]["success_rate"].get<double>()) / 2));

  // The report: the tables and a plot per metric, nothing fetched from the network.
  const std::string html = readText(box.path("report") / "index.html");
  CHECK(html.find("<svg") != std::string::npos);
  CHECK(html.find("Bellman residual against updates") != std::string::npos);
  CHECK(html.find("src=") == std::string::npos);  // self-contained: it opens from disk, offline
  CHECK(html.find("href=\"http") == std::string::npos);
  CHECK(readText(box.path("report") / "results.csv").find("q_learning,2,") != std::string::npos);
  CHECK(json::parse(readText(box.path("report") / "results.json"))["runs"].size() == 3);

  // A second run reuses every bundle: nothing is trained again.
  const Run again = box.run(kCompare + " --seeds 1 --json");
  REQUIRE(again.status == 0);
  CHECK(again.err.find("train hit:") == std::string::npos);
  CHECK(again.report()["runs"][0]["success_rate"] == q1["success_rate"]);
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
