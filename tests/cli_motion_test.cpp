// Capture from elsewhere through the real binary (a skeleton
// without finger joints, a boxer knocked down), a mismatched ASF, and how far the capture
// travels against the behaviours' grids.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "cli_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_motion_test {

using namespace mgrl::test;
using Catch::Contains;

namespace {

const std::filesystem::path kBoxing = std::filesystem::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing.yaml";

std::size_t countLines(const std::string& text, const std::string& needle) {
  const auto all = lines(text);
  return static_cast<std::size_t>(
      std::count_if(all.begin(), all.end(), [&](const std::string& l) { return l.find(needle) != std::string::npos; }));
}

}  // namespace

TEST_CASE("mgrl inspect reads a 21-joint boxer without fingers and says once where its fists are", "[cli]") {
  CliSandbox box("cli-motion-fist");
  const Run run = runMgrl("inspect " + shellWord(testData() / "boxer21.bvh"), box.dir());
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(countLines(run.err, "no fist joint") == 1);
  CHECK_THAT(run.err, Contains("mgrl: warning: ") &&
                          Contains("boxer21.bvh: no fist joint (a name like leftfingerbase), using LeftWrist's end site "
                                   "for left_fist and RightWrist's end site for right_fist"));
  // The standing punch counts, the one thrown lying on the floor does not.
  CHECK_THAT(run.out, Contains("effective hits: left 1 in 1 punch, right 0 in 0 punches"));
  CHECK_THAT(run.out, Contains("45 frames knocked down"));
  CHECK_THAT(run.out, Contains("height 1.628 m (file units: cm)"));
}

TEST_CASE("mgrl inspect --json reports the standing and rest-pose heights and knocked-down frames", "[cli]") {
  CliSandbox box("cli-motion-height");
  const Run run = runMgrl("inspect --json " + shellWord(testData() / "boxer21.bvh"), box.dir());
  const nlohmann::json file = run.report()["files"][0];
  CHECK(file["height_m"].get<double>() == Approx(1.628).margin(0.001));
  CHECK(file["rest_height_m"].get<double>() == Approx(1.7516));
  CHECK(file["knockdown_frames"] == 45);
  CHECK(file["punches"]["total"] == 1);
}

TEST_CASE("mgrl inspect warns when an AMC is given another CMU subject's ASF", "[cli][data]") {
  CliSandbox box("cli-motion-asf");
  const auto folder = mocap() / "cmu" / "asfamc";
  const Run other = runMgrl("inspect " + shellWord(folder / "13_17.amc") + " --asf " + shellWord(folder / "07.asf"), box.dir());
  REQUIRE(other.status == 0);
  CHECK_THAT(other.err, Contains("13_17.amc: expected the skeleton of subject 13 (13.asf), found 07.asf (subject 07)"));
  const Run own = runMgrl("inspect " + shellWord(folder / "13_17.amc") + " --asf " + shellWord(folder / "13.asf"), box.dir());
  REQUIRE(own.status == 0);
  CHECK(own.err.empty());
}

TEST_CASE("mgrl graph reports how far the capture travels and warns about grids beyond it", "[cli][data][graph]") {
  CliSandbox box("cli-motion-travel");
  // The shipped boxer: its 10 s walk through the graph covers the 2 m approach grid.
  const Run boxing = runMgrl("graph " + shellWord(kBoxing) + " --json" + box.where(), box.dir());
  const nlohmann::json travel = boxing.report()["travel"];
  CHECK(travel["clip_travel_m"].get<double>() > 0.5);
  CHECK(travel["clip_travel_m"].get<double>() < 1.5);
  CHECK(travel["walk_travel_m"].get<double>() > 2.0);
  CHECK(travel["action_travel_m"].get<double>() > 0.2);
  CHECK(travel["grid_reach_m"]["approach"].get<double>() == Approx(2.0));
  CHECK(travel["warnings"].empty());
  CHECK(countLines(boxing.err, "warning") == 0);
  // A minute of capture: no library options, nothing said of them.
  CHECK(boxing.report()["library"].is_null());

  // The same capture with a 30 m approach grid: far beyond anything it travels.
  std::string yaml = readText(kBoxing);
  const auto at = yaml.find("radius: 2.0");
  REQUIRE(at != std::string::npos);
  yaml.replace(at, 11, "radius: 30.0");
  const auto far = box.path("far.yaml");
  {
    std::ofstream(far) << yaml;
  }
  const Run run = runMgrl("graph " + shellWord(far) + box.where(), box.dir());
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Contains("travel          root up to ") && Contains("grids reach approach 30.00 m"));
  CHECK(countLines(run.err, "warning") == 1);
  CHECK_THAT(run.err, Contains("mgrl: graph: warning: behaviors.approach: its grid reaches 30.00 m from the avatar, "
                               "but the capture carries the root at most"));
  CHECK_THAT(run.out, Contains("frames          1960 in 2 files"));
}

TEST_CASE("mgrl inspect --punch-min-speed auto chooses and reports each file's threshold, a bad value is refused",
          "[cli][data]") {
  CliSandbox box("cli-motion-auto");
  const std::string file = shellWord(mocap() / "cmu/bvh/13_17_boxing.bvh");
  const Run chosen = runMgrl("inspect --fps 30 --json --punch-min-speed auto " + file, box.dir());
  INFO(chosen.err);
  REQUIRE(chosen.status == 0);
  const auto report = chosen.report()["files"][0];
  const auto speeds = report["punch_min_speed_mps"];
  CHECK(speeds[0].get<double>() > 1.5);
  CHECK(speeds[0].get<double>() < 2.3);
  CHECK(speeds[0] == speeds[1]);  // CMU's fists are knuckles: no wrist scaling
  CHECK_THAT(report["punch_min_speed_auto"].get<std::string>(),
             Contains("punch threshold auto: ") && Contains("the Otsu split of"));
  const Run text = runMgrl("inspect --fps 30 --punch-min-speed auto " + file, box.dir());
  CHECK_THAT(text.out, Contains("  punch threshold auto: "));
  // Given, it is what the report says, with no auto sentence.
  const Run given = runMgrl("inspect --fps 30 --json --punch-min-speed 2.5 " + file, box.dir());
  REQUIRE(given.status == 0);
  CHECK(given.report()["files"][0]["punch_min_speed_mps"][0].get<double>() == Approx(2.5));
  CHECK(given.report()["files"][0]["punch_min_speed_auto"].is_null());
  for (const char* bad : {"fast", "2.5x", "0", "-1"}) {
    CAPTURE(bad);
    const Run refused = runMgrl(std::string("inspect --punch-min-speed ") + bad + " " + file, box.dir());
    CHECK(refused.status == 1);
    CHECK(refused.out.empty());
    CHECK_THAT(refused.err, Contains(std::string("--punch-min-speed: expected a speed in (0, 100] m/s or auto, found '") +
                                     bad + "'"));
  }
}

}  // namespace cli_motion_test
