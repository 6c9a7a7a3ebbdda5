#include <cstdio>
#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_json_test {

namespace {

struct Run {
  int status;
  std::string out;
};

// Runs the real mgrl binary, capturing stdout (stderr goes to /dev/null).
Run runMgrl(const std::string& arguments) {
  const std::string command = std::string("'") + MGRL_BINARY + "' " + arguments + " 2>/dev/null";
  std::FILE* pipe = popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string out;
  char buffer[4096];
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, got);
  return {pclose(pipe), out};
}

}  // namespace

TEST_CASE("mgrl inspect --json reports the contract keys for real capture", "[cli][data]") {
  const auto bvh = (mgrl::test::mocap() / "cmu/bvh/13_17_boxing.bvh").string();
  const auto amc = (mgrl::test::mocap() / "cmu/asfamc/13_17.amc").string();
  const Run run = runMgrl("inspect --json '" + bvh + "' '" + amc + "'");
  REQUIRE(run.status == 0);
  const nlohmann::json report = nlohmann::json::parse(run.out);  // stdout is one JSON object
  REQUIRE(report["files"].size() == 2);
  for (const auto& file : report["files"]) {
    CHECK(file["joints"] == 31);
    CHECK(file["joint_names"].size() == 31);
    CHECK(file["frames"] == 4840);
    CHECK(file["fps"].get<double>() == Approx(120));
    CHECK(file["duration_s"].get<double>() == Approx(40.33).margin(0.01));
    CHECK(file["height_m"].get<double>() == Approx(1.63).margin(0.02));
    CHECK(file["contact_frames"]["left"].get<int>() > 1000);
    CHECK(file["contact_frames"]["right"].get<int>() > 1000);
    const auto& hits = file["effective_hits"];
    CHECK(hits["total"].get<int>() == hits["left"].get<int>() + hits["right"].get<int>());
    CHECK(hits["total"].get<int>() > 200);
  }
  // The names a body point may use: the joints, and the roles with their joints, in each
  // file's own naming.
  const auto& bvhFile = report["files"][0];
  const auto& amcFile = report["files"][1];
  CHECK(bvhFile["joint_names"][0] == "Hips");
  CHECK(bvhFile["roles"]["left_fist"] == "LeftFingerBase");
  CHECK(bvhFile["roles"]["right_toe"] == "RightToeBase");
  CHECK(amcFile["joint_names"][0] == "root");
  CHECK(amcFile["roles"]["left_fist"] == "lhand");
  CHECK(amcFile["roles"]["right_toe"] == "rtoes");
  // The BVH and its ASF/AMC original are the same capture.
  CHECK(report["files"][0]["effective_hits"] == report["files"][1]["effective_hits"]);
  CHECK(report["files"][0]["contact_frames"] == report["files"][1]["contact_frames"]);
}

TEST_CASE("mgrl inspect --fps resamples before annotating", "[cli][data]") {
  const auto bvh = (mgrl::test::mocap() / "cmu/bvh/13_18_boxing.bvh").string();
  const Run run = runMgrl("inspect --json --fps 30 '" + bvh + "'");
  REQUIRE(run.status == 0);
  const auto file = nlohmann::json::parse(run.out)["files"][0];
  CHECK(file["frames"] == 750);
  CHECK(file["fps"].get<double>() == Approx(30));
  CHECK(file["file_fps"].get<double>() == Approx(120));
}

TEST_CASE("a failing mgrl inspect prints nothing on stdout", "[cli][data]") {
  const auto bvh = (mgrl::test::mocap() / "cmu/bvh/13_18_boxing.bvh").string();
  const Run run = runMgrl("inspect --json '" + bvh + "' no_such_file.bvh");
  CHECK(run.status != 0);
  CHECK(run.out.empty());
}

TEST_CASE("mgrl graph --json reports the contract keys and reuses its cache", "[cli][data][graph]") {
  const auto cache = std::filesystem::temp_directory_path() / "mgrl_cli_graph_cache";
  std::filesystem::remove_all(cache);
  const std::string args = std::string("graph '") + MGRL_SOURCE_DIR + "/scenarios/boxing.yaml' --json --cache '" +
                           cache.string() + "'";
  for (bool cached : {false, true}) {
    const Run run = runMgrl(args);
    REQUIRE(run.status == 0);
    const auto json = nlohmann::json::parse(run.out);
    for (const char* key : {"frames_total", "frames_in_scc", "states", "actions", "mean_action_frames",
                            "min_action_frames", "max_action_frames", "build_seconds"})
      CHECK(json.contains(key));
    CHECK(json["frames_total"] == 1960);
    CHECK(json["states"].get<int>() >= 30);
    CHECK(json["actions"].get<int>() >= 1000);
    CHECK(json["cached"] == cached);
  }
  std::filesystem::remove_all(cache);
}

}  // namespace cli_json_test
