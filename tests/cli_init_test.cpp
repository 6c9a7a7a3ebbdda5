// `mgrl init` through the real binary: a starter scenario for capture the
// repository has never seen, which builds, trains and beats random actions; and what it
// refuses without leaving a file behind.
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "cli_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_init_test {

using namespace mgrl::test;
using Catch::Contains;

TEST_CASE("mgrl init writes a scenario for CMU boxing that builds, trains and beats random actions",
          "[cli][data][slow]") {
  CliSandbox box("cli-init-cmu");
  const std::filesystem::path out = box.path("mine.yaml");
  const Run init = runMgrl("init " + shellWord(mocap() / "cmu/bvh/13_17_boxing.bvh") + " --out " + shellWord(out) +
                               " --data " + shellWord(mocap()),
                           box.dir());
  REQUIRE(init.status == 0);
  // The paper's graph settings keep most of this capture: init stops at the first try.
  CHECK_THAT(init.out, Contains("wrote " + out.string()));
  CHECK_THAT(init.out, Contains("graph: threshold 0.45, left_foot_liftoff: 96 % of frames kept"));
  CHECK_THAT(init.out, Contains("behaviours: approach, hit"));
  CHECK_THAT(init.out, Contains("mgrl train " + out.string()));
  const std::string yaml = readText(out);
  CHECK_THAT(yaml, Contains("name: mine"));
  CHECK_THAT(yaml, Contains("- \"cmu/bvh/13_17_boxing.bvh\""));  // under the data folder: relative
  CHECK_THAT(yaml, Contains("units: cmu"));
  CHECK_THAT(yaml, Contains("#   left_fist: LeftFingerBase"));
  CHECK_THAT(yaml, Contains("learner: {type: value_iteration}"));
  CHECK_FALSE(std::filesystem::exists(box.path("mine.yaml.init-check.yaml")));

  const Run train = runMgrl("train " + shellWord(out) + box.where() + " --json", box.dir());
  REQUIRE(train.status == 0);
  const Run eval = runMgrl("eval " + shellWord(out) + box.where() + " --trials 100 --seed 3 --json", box.dir());
  const nlohmann::json report = eval.report();
  const double policy = report["success_rate"], random = report["random_baseline"]["success_rate"];
  CAPTURE(policy, random);
  CHECK(policy >= 0.8);
  CHECK(policy >= 4 * random);
}

TEST_CASE("mgrl init reports in JSON what it found and chose", "[cli][data]") {
  CliSandbox box("cli-init-json");
  const std::filesystem::path out = box.path("boxing13.yaml");
  const Run run = runMgrl("init " + shellWord(mocap() / "cmu/bvh/13_17_boxing.bvh") + " --out " + shellWord(out) +
                              " --json --data " + shellWord(mocap()),
                          box.dir());
  const nlohmann::json r = run.report();
  CHECK(r["scenario"] == out.string());
  CHECK(r["name"] == "boxing13");
  CHECK(r["units"] == nlohmann::json{"cmu"});
  CHECK(r["root_motion_joint"] == "Hips");
  CHECK(r["graph"]["threshold"] == 0.45);
  CHECK(r["graph"]["contact_event"] == "left_foot_liftoff");
  CHECK(r["graph"]["usable"] == true);
  CHECK(r["graph"]["kept_share"].get<double>() > 0.9);
  CHECK(r["effective_punches"].get<int>() > 20);  // punches, not frames
  CHECK(r["behaviors"] == nlohmann::json{"approach", "hit"});
  CHECK(r["next"].size() == 4);
}

TEST_CASE(
    "mgrl init on a game studio's library: locomotion swings are no punches, and the graph keeps most of "
    "the clips, gestures included, in bounded states",
    "[cli][data]") {
  CliSandbox box("cli-init-library");
  const std::filesystem::path out = box.path("library.yaml");
  const Run run = runMgrl("init " + shellWord(mocap() / "bandai_namco_1" / "data") + "/*.bvh --out " + shellWord(out) +
                              " --json --data " + shellWord(mocap()),
                          box.dir());
  const nlohmann::json r = run.report();
  CHECK(r["frames"] == 31914);
  // 18 minutes: a library. Any contact change first, and 80 % of the frames kept.
  CHECK(r["graph"]["contact_event"] == "any_contact_change");
  CHECK(r["graph"]["usable"] == true);
  CHECK(r["graph"]["kept_share"].get<double>() >= 0.8);
  // Its walks, runs and dashes swing their arms: 231 punches without the swing rule, and
  // about 40 with it (the punch, kick, slash and dance clips, a wave).
  CHECK(r["effective_punches"].get<int>() < 60);
  // The body travels half of the time: a library of locomotion walks to a goal.
  CHECK(r["locomotion_share"].get<double>() > 0.4);
  CHECK(r["behaviors"] == nlohmann::json{"goal"});
  const std::string yaml = readText(out);
  CHECK_THAT(yaml, Contains("swing_travel_mps: 0.9"));
  CHECK_THAT(yaml, Contains("# A library (18 minutes of capture, more than 10)"));

  const Run graph = runMgrl("graph " + shellWord(out) + box.where() + " --json", box.dir());
  const nlohmann::json g = graph.report();
  CHECK(g["library"]["max_out_degree"] == 32);
  CHECK(g["library"]["standing_cut_frames"].get<int>() > 100);
  CHECK(g["scc_fraction"].get<double>() >= 0.8);
  // Reused from the cache, the graph says what the build did.
  const Run again = runMgrl("graph " + shellWord(out) + box.where() + " --json", box.dir());
  CHECK(again.report()["cached"] == true);
  CHECK(again.report()["library"] == g["library"]);
  const Run text = runMgrl("graph " + shellWord(out) + box.where(), box.dir());
  CHECK_THAT(text.out, Contains("library         at most 32 actions a state: "));
  const double perState = g["actions"].get<double>() / g["states"].get<double>();
  CAPTURE(perState);
  CHECK(perState <= 32);
  // Every kind of clip is in the graph, the standing gestures too.
  std::map<std::string, std::pair<double, double>> kinds;  // frames in, frames
  for (const nlohmann::json& clip : g["clips"]) {
    const std::string name = clip["clip"];
    const std::string kind = name.substr(10, name.find('_', 10) - 10);
    kinds[kind].first += clip["in_scc"].get<double>() * clip["frames"].get<double>();
    kinds[kind].second += clip["frames"].get<double>();
  }
  CHECK(kinds.size() == 16);
  for (const auto& [kind, share] : kinds) {
    CAPTURE(kind);
    CHECK(share.first / share.second >= 0.7);
  }
}

// The graph settings tried, in order, from the starter's comment lines: "threshold event".
std::vector<std::string> triesOf(const std::string& yaml) {
  std::vector<std::string> tries;
  std::istringstream lines(yaml);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string hash, word, threshold, event;
    if (words >> hash >> word >> threshold >> event && hash == "#" && word == "threshold")
      tries.push_back(threshold + " " + event);
  }
  return tries;
}

TEST_CASE(
    "mgrl init tries the paper's contact event at every threshold before any contact change, keeps the best try "
    "when none is enough, and reads SNU's centimetres",
    "[cli][data]") {
  CliSandbox box("cli-init-tries");
  const std::vector<std::string> liftoff = {"0.45 left_foot_liftoff", "0.6 left_foot_liftoff", "0.75 left_foot_liftoff",
                                            "0.9 left_foot_liftoff", "1.2 left_foot_liftoff"};

  // CMU's martial arts (815 frames): no threshold with the left foot's lift-off keeps 60 %
  // of the frames, any contact change does at the paper's threshold.
  const std::filesystem::path arts = box.path("arts.yaml");
  const Run first = runMgrl("init " + shellWord(mocap() / "cmu/bvh/135_06_martial_arts.bvh") + " --out " +
                                shellWord(arts) + " --json --data " + shellWord(mocap()),
                            box.dir());
  const nlohmann::json a = first.report();
  CHECK(a["units"] == nlohmann::json{"cmu"});
  CHECK(a["graph"]["contact_event"] == "any_contact_change");
  CHECK(a["graph"]["threshold"] == 0.45);
  CHECK(a["graph"]["usable"] == true);
  std::vector<std::string> expected = liftoff;
  expected.push_back("0.45 any_contact_change");
  CHECK(triesOf(readText(arts)) == expected);

  // Three short SNU clips (213 frames, centimetres): nothing keeps 60 %; the try that kept
  // most frames (the first of three that keep 37 %) is written, and said to be the best found.
  const std::filesystem::path snu = box.path("snu.yaml");
  const std::filesystem::path clips = mocap() / "snu_martial_arts/motion";
  const Run best =
      runMgrl("init " + shellWord(clips / "16_08_1.bvh") + " " + shellWord(clips / "16_21_1.bvh") + " " +
                  shellWord(clips / "16_24_1.bvh") + " --out " + shellWord(snu) + " --data " + shellWord(mocap()),
              box.dir());
  INFO(best.err);
  REQUIRE(best.status == 0);
  CHECK_THAT(best.out, Contains("units cm"));
  CHECK_THAT(best.out, Contains("graph: threshold 0.75, any_contact_change: 37 % of frames kept, 2 states, 4 actions "
                                "(the best found; more capture would help)"));
  const std::string yaml = readText(snu);
  CHECK_THAT(yaml, Contains("units: cm"));
  CHECK_THAT(yaml, Contains("  threshold: 0.75\n  contact_event: any_contact_change\n  min_states: 2\n"));
  expected = liftoff;
  for (const char* t : {"0.45", "0.6", "0.75", "0.9", "1.2"})
    expected.push_back(std::string(t) + " any_contact_change");
  CHECK(triesOf(yaml) == expected);
  // What it wrote builds: the best graph's two states.
  const Run graph = runMgrl("graph " + shellWord(snu) + box.where() + " --json", box.dir());
  INFO(graph.err);
  REQUIRE(graph.status == 0);
  CHECK(graph.report()["states"] == 2);
}

TEST_CASE("mgrl init refuses what it cannot use and leaves no file behind", "[cli]") {
  CliSandbox box("cli-init-refuse");
  const std::filesystem::path out = box.path("new.yaml");

  // Too little capture for a graph: four frames.
  Run run = runMgrl("init " + shellWord(testData() / "tiny.bvh") + " --out " + shellWord(out), box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("init: expected a graph of at least 10 states from these files, found at "
                                           "most 0") &&
                                      Contains("4 frames, 0.1 s: too little capture"));
  CHECK(run.out.empty());
  CHECK_FALSE(std::filesystem::exists(out));
  CHECK_FALSE(std::filesystem::exists(box.path("new.yaml.init-check.yaml")));

  // A file that is not there.
  run = runMgrl("init " + shellWord(box.path("missing.bvh")) + " --out " + shellWord(out), box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("missing.bvh"));
  CHECK_FALSE(std::filesystem::exists(out));

  // Files of two skeletons.
  run = runMgrl("init " + shellWord(testData() / "boxer21.bvh") + " " + shellWord(testData() / "tiny.bvh") +
                    " --out " + shellWord(out),
                box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("boxer21.bvh and tiny.bvh have different skeletons"));
  CHECK_FALSE(std::filesystem::exists(out));

  // An existing scenario stays as it is without --force.
  { std::ofstream(out) << "# mine\n"; }
  run = runMgrl("init " + shellWord(testData() / "tiny.bvh") + " --out " + shellWord(out), box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("already exists; expected a new file (--force replaces it)"));
  CHECK(readText(out) == "# mine\n");

  // A frame rate out of range.
  run = runMgrl("init " + shellWord(testData() / "tiny.bvh") + " --fps 0 --out " + shellWord(box.path("other.yaml")),
                box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("--fps: expected a frame rate in (0, 1000], found 0"));

  // Units it does not know.
  run = runMgrl("init " + shellWord(testData() / "tiny.bvh") + " --units furlong --out " +
                    shellWord(box.path("other.yaml")),
                box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("--units: expected one of auto, m, cm, inch, cmu, found 'furlong'"));
  CHECK_FALSE(std::filesystem::exists(box.path("other.yaml")));

  // A folder to write into that is not there: refused before any work, nothing written.
  run = runMgrl("init " + shellWord(testData() / "tiny.bvh") + " --out " + shellWord(box.path("no/such/dir/x.yaml")),
                box.dir());
  CHECK(run.status != 0);
  CHECK_THAT(run.lastErrorLine(), Contains("no/such/dir"));
  CHECK_FALSE(std::filesystem::exists(box.path("no")));
}

}  // namespace cli_init_test
