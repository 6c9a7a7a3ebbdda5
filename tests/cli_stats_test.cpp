// `mgrl stats` on what `mgrl simulate --bvh-out` writes (random controller: no training),
// through the real binary: the --json keys, simulate's partners, and --compare against a
// real SNU bout.
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace cli_stats_test {

using mgrl::test::shellWord;
using nlohmann::json;

TEST_CASE("mgrl stats reads a simulate --bvh-out folder", "[stats][cli][data]") {
  mgrl::test::CliSandbox box("mgrl_cli_stats");
  const std::string boxing = std::string(MGRL_SOURCE_DIR) + "/scenarios/boxing.yaml";
  const auto bvh = box.path("bout");
  const mgrl::test::Run simulated =
      mgrl::test::runMgrl("simulate " + shellWord(boxing) + box.where() +
                              " --controller random --avatars 2 --seconds 10 --seed 3 --json --bvh-out " +
                              shellWord(bvh),
                          box.dir());
  INFO("simulate stderr: " << simulated.err);
  REQUIRE(simulated.status == 0);

  const mgrl::test::Run run = mgrl::test::runMgrl("stats " + shellWord(bvh) + " --json", box.dir());
  const json r = run.report();
  REQUIRE(r["bouts"].size() == 1);
  const json& bout = r["bouts"][0];
  CHECK(bout["pairing"] == "partners");  // avatar_000.bvh and avatar_001.bvh
  CHECK(bout["fighters"] == 2);
  CHECK(bout["files"].size() == 2);      // manifest.json is not a fighter
  CHECK(bout["fps"][0].get<double>() == Approx(30).epsilon(1e-3));
  CHECK(bout["seconds"].get<double>() == Approx(10).margin(0.1));
  for (const char* key :
       {"distance_m", "facing_deg", "planted_foot_speed_mps", "planted_ankle_speed_mps", "planted_toe_speed_mps"}) {
    INFO(key);
    REQUIRE(bout[key]["median"].is_number());
    CHECK(bout[key]["deciles"].size() == 11);
  }
  for (const char* key :
       {"strikes_per_fighter_minute", "landed_per_fighter_minute", "reversals_per_frame", "reversals_per_second",
        "pelvis_close_share", "capsule_overlap_share", "forearm_inside_share"}) {
    INFO(key);
    CHECK(bout[key].is_number());
  }
  CHECK(bout["joint_step_m"]["max"].is_number());
  CHECK(bout["joint_step_m"]["p99"].is_number());
  // Metres, not simulate's centimetres: partners start 1.6 m apart (world.start_distance).
  CHECK(bout["distance_m"]["deciles"][10].get<double>() < 20);
  CHECK(r["pooled"]["fighters"] == 2);

  const mgrl::test::Run compared = mgrl::test::runMgrl(
      "stats --json --data " + shellWord(mgrl::test::mocap()) + " --compare 'snu_martial_arts/motion/s_005_1_*.bvh' -- " +
          shellWord(bvh),
      box.dir());
  const json c = compared.report();
  CHECK(c["real"]["pooled"]["bouts"] == 1);
  CHECK(c["synthetic"]["pooled"]["bouts"] == 1);
  CHECK(c["wasserstein1"]["distance_m"].get<double>() >= 0);
  CHECK(c["wasserstein1"]["facing_deg"].get<double>() >= 0);
}

}  // namespace cli_stats_test
