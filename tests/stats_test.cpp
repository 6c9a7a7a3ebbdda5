// mgrl stats' measures (app/bout_stats.*, app/stats_command.*) on tiny hand-checkable bouts
// in tests/data/stats (a 170 cm stick figure, T-pose arms, rigid legs; see its README), on
// the real SNU sparring capture, and its bad-input errors.
#include <cmath>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "mgrl/learning/real_bouts.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/runtime/bout_stats.hpp"
#include "stats_command.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace stats_test {

namespace fs = std::filesystem;
using Catch::Contains;
using Catch::Matchers::WithinAbs;
using mgrl::BoutStats;
using mgrl::StatsParams;

namespace {

fs::path statsData() { return mgrl::test::testData() / "stats"; }

BoutStats measureFolder(const std::string& folder, const StatsParams& params = {},
                        std::vector<std::string>* warnings = nullptr) {
  const mgrl::BoutFiles files = mgrl::resolveBout((statsData() / folder).string(), {});
  const mgrl::Bout bout = mgrl::loadBout(files.name, files.files, params, [&](const std::string& m) {
    if (warnings) warnings->push_back(m);
  });
  return mgrl::measureBout(bout, params);
}

double median(const std::vector<double>& v) { return mgrl::quantile(v, 0.5); }

}  // namespace

TEST_CASE("stats: two fighters standing 1 m apart face to face", "[stats]") {
  const BoutStats s = measureFolder("stand");
  CHECK(s.fighters == 2);
  CHECK(s.frames == 30);
  CHECK_THAT(s.seconds, WithinAbs(1.0, 1e-4));
  REQUIRE(s.distance_m.size() == 60);  // per fighter-frame
  CHECK_THAT(median(s.distance_m), WithinAbs(1.0, 1e-9));
  CHECK_THAT(mgrl::quantile(s.facing_deg, 1.0), WithinAbs(0.0, 1e-3));
  CHECK(s.reversals == 0);
  CHECK(s.rootSteps == 58);
  CHECK(s.punches + s.kicks == 0);
  CHECK(s.closeFrames == 0);
  CHECK(s.overlapFrames == 0);
  // Feet flat on the floor, still: planted every frame, at speed 0; nothing moves.
  CHECK(s.plantedFootSpeed_mps.size() == 2 * 2 * 30);
  CHECK_THAT(mgrl::quantile(s.plantedFootSpeed_mps, 1.0), WithinAbs(0.0, 1e-9));
  CHECK(s.plantedAnkleSpeed_mps.size() == s.plantedFootSpeed_mps.size());
  CHECK(s.plantedToeSpeed_mps.size() == s.plantedFootSpeed_mps.size());
  CHECK_THAT(mgrl::quantile(s.jointStep_m, 1.0), WithinAbs(0.0, 1e-9));
}

TEST_CASE("stats: a foot pivoting on its still ankle skates at the toe, which each foot joint's speed shows",
          "[stats]") {
  // pivot/: fighter 1 of stand/ turns its left foot about the ankle, 3 degrees a frame at
  // 30 fps (1.57 rad/s); the toe, 10 cm in front of the ankle on the ground, sweeps round
  // at 0.157 m/s. The slower of ankle and toe reads 0 throughout: it cannot see this.
  const BoutStats s = measureFolder("pivot");
  REQUIRE(s.plantedFootSpeed_mps.size() == 2 * 2 * 30);  // every foot planted every frame
  REQUIRE(s.plantedAnkleSpeed_mps.size() == s.plantedFootSpeed_mps.size());
  REQUIRE(s.plantedToeSpeed_mps.size() == s.plantedFootSpeed_mps.size());
  CHECK_THAT(mgrl::quantile(s.plantedFootSpeed_mps, 1.0), WithinAbs(0.0, 1e-9));
  CHECK_THAT(mgrl::quantile(s.plantedAnkleSpeed_mps, 1.0), WithinAbs(0.0, 1e-9));
  // One foot of the four turns: a quarter of the samples, its inner frames at the circle's
  // speed (a central difference over 6 degrees: 0.157 x sin(3 deg) / (3 deg) = 0.1570).
  std::size_t moving = 0;
  for (const double v : s.plantedToeSpeed_mps)
    if (v > 0.01) {
      ++moving;
      CHECK_THAT(v, WithinAbs(0.157, 0.003));
    }
  CHECK(moving >= 28);
  CHECK(moving <= 30);
  CHECK_THAT(mgrl::quantile(s.plantedToeSpeed_mps, 1.0), WithinAbs(0.157, 0.003));
}

TEST_CASE("stats: a fighter walking back and forth reverses three times", "[stats]") {
  // Fighter 1 walks along +X at 1.5 m/s, turns back every 10 frames (steps 10, 20 and 30
  // point against the one before); fighter 2 stands 2 m away.
  const BoutStats s = measureFolder("walk");
  CHECK(s.reversals == 3);
  CHECK(s.rootSteps == 2 * 39);
  // The largest joint step is the walker's 5 cm per frame.
  CHECK_THAT(mgrl::quantile(s.jointStep_m, 1.0), WithinAbs(0.05, 1e-6));
  CHECK_THAT(mgrl::quantile(s.jointSpeed_mps, 1.0), WithinAbs(1.5, 1e-4));  // at 30 fps
  // Below the jitter threshold, nothing counts.
  StatsParams slowOnly;
  slowOnly.reversalMinSpeed_mps = 2.0;
  CHECK(measureFolder("walk", slowOnly).reversals == 0);
}

TEST_CASE("stats: a lunging left fist is one effective punch, landed only when the opponent is in reach", "[stats]") {
  // Fighter 1 (facing +Z) lunges 40 cm along +X at 3 m/s: its left arm points along +X, so
  // the fist moves along the forearm; fighter 2 stands facing it, 1.3 m or 3 m away. The
  // arm does not move on the body, so by default it is an arm swing carried by the body
  // (AnnotationParams::punchMinBodySpeed_mps); with that test off it is one punch.
  CHECK(measureFolder("punch_near").punches == 0);
  StatsParams carried;
  carried.annotation.punchMinBodySpeed_mps = 0;
  const BoutStats near = measureFolder("punch_near", carried);
  CHECK(near.punches == 1);
  CHECK(near.kicks == 0);
  CHECK(near.landed == 1);
  const BoutStats far = measureFolder("punch_far", carried);
  CHECK(far.punches == 1);
  CHECK(far.landed == 0);
  // A smaller reach: the fist tip stops 7 cm short of the spine capsule's surface.
  StatsParams tight = carried;
  tight.landRadius_m = 0.02;
  CHECK(measureFolder("punch_near", tight).landed == 0);
  // Facing: fighter 1 looks along +Z at an opponent along +X (90 deg), fighter 2 at it (0).
  CHECK_THAT(mgrl::quantile(near.facing_deg, 0.0), WithinAbs(0.0, 1e-3));
  CHECK_THAT(mgrl::quantile(near.facing_deg, 1.0), WithinAbs(90.0, 1e-3));
}

TEST_CASE("stats: a punch that meets the opponent's forearm first is blocked, not landed", "[stats]") {
  // punch_near with fighter 2's left forearm across the front of its chest (the README).
  StatsParams carried;
  carried.annotation.punchMinBodySpeed_mps = 0;
  const BoutStats guarded = measureFolder("punch_guarded", carried);
  CHECK(guarded.punches == 1);
  CHECK(guarded.blocked == 1);
  CHECK(guarded.landed == 0);
  // Nothing blocks the same punch without the guard, nor with blocks turned off.
  const BoutStats open = measureFolder("punch_near", carried);
  CHECK(open.blocked == 0);
  CHECK(open.landed == 1);
  StatsParams noBlocks = carried;
  noBlocks.blockRadius_m = 0;
  const BoutStats through = measureFolder("punch_guarded", noBlocks);
  CHECK(through.blocked == 0);
  CHECK(through.landed == 1);
  // The fist passes 7 cm from the forearm's axis: a 5 cm block radius lets it land.
  StatsParams thin = carried;
  thin.blockRadius_m = 0.05;
  CHECK(measureFolder("punch_guarded", thin).landed == 1);
}

TEST_CASE("stats: strikes are counted each way, per fighter and for the stronger side of each pair", "[stats]") {
  StatsParams carried;
  carried.annotation.punchMinBodySpeed_mps = 0;
  // punch_near: fighter 1 lands its one punch, fighter 2 throws none.
  const BoutStats near = measureFolder("punch_near", carried);
  REQUIRE(near.sides.size() == 2);
  CHECK(fs::path(near.sides[0].source).filename() == "fighter_1.bvh");
  CHECK(near.sides[0].strikes == 1);
  CHECK(near.sides[0].landed == 1);
  CHECK(near.sides[0].blocked == 0);
  CHECK(near.sides[1].strikes == 0);
  CHECK(near.sides[1].landed == 0);
  CHECK_THAT(near.sides[0].seconds, WithinAbs(near.seconds, 1e-12));
  CHECK(near.landedByMore == 1);
  CHECK(near.landedInPairs == 1);
  // The guard takes it: blocked on fighter 1's side, nothing landed in the pair.
  const BoutStats guarded = measureFolder("punch_guarded", carried);
  CHECK(guarded.sides[0].blocked == 1);
  CHECK(guarded.sides[0].landed == 0);
  CHECK(guarded.landedInPairs == 0);
  const nlohmann::json j = mgrl::statsJson(near);
  CHECK(j["by_fighter"][0]["file"] == "fighter_1.bvh");
  CHECK(j["by_fighter"][0]["landed"] == 1);
  CHECK(j["by_fighter"][1]["strikes"] == 0);
  CHECK(j["landed_by_stronger_share"] == 1.0);
  CHECK(mgrl::statsJson(guarded)["landed_by_stronger_share"].dump() == "null");  // nothing landed: no share
  // Four fighters paired by nearness have no fixed pairs; simulate's partners do.
  CHECK(measureFolder("four").sides.size() == 4);
  const BoutStats partners = measureFolder("partners");
  CHECK(partners.sides.size() == 4);
  CHECK(partners.landedInPairs == 0);
  // Pooled: every side kept, the pairs' counts summed.
  const BoutStats p = mgrl::pool({near, guarded, near}, "pooled");
  CHECK(p.sides.size() == 6);
  CHECK(p.landedByMore == 2);
  CHECK(p.landedInPairs == 2);
}

TEST_CASE("stats: pooling sums every count and time and joins every sample list and side", "[stats]") {
  // Every field of BoutStats set, one bout's to 1 (or {1}), the other's to 2 (or {2, 2}).
  const auto filled = [](std::size_t n) {
    BoutStats b;
    const double x = static_cast<double>(n);
    for (std::size_t* count :
         {&b.bouts, &b.fighters, &b.frames, &b.rootSteps, &b.reversals, &b.punches, &b.kicks, &b.landed, &b.blocked,
          &b.landedByMore, &b.landedInPairs, &b.pairFrames, &b.closeFrames, &b.overlapFrames, &b.forearmInsideFrames})
      *count = n;
    for (double* sum : {&b.seconds, &b.fighterSeconds, &b.stepSeconds}) *sum = x;
    for (std::vector<double>* samples :
         {&b.fps, &b.distance_m, &b.facing_deg, &b.plantedFootSpeed_mps, &b.plantedAnkleSpeed_mps,
          &b.plantedToeSpeed_mps, &b.jointStep_m, &b.jointSpeed_mps})
      samples->assign(n, x);
    b.sides.assign(n, BoutStats::Side{"f" + std::to_string(n), n, n, n, x});
    return b;
  };
  const BoutStats p = mgrl::pool({filled(1), filled(2)}, "pooled");
  CHECK(p.name == "pooled");
  for (std::size_t count :
       {p.bouts, p.fighters, p.frames, p.rootSteps, p.reversals, p.punches, p.kicks, p.landed, p.blocked,
        p.landedByMore, p.landedInPairs, p.pairFrames, p.closeFrames, p.overlapFrames, p.forearmInsideFrames})
    CHECK(count == 3);
  for (double sum : {p.seconds, p.fighterSeconds, p.stepSeconds}) CHECK(sum == 3.0);
  for (const std::vector<double>& samples :
       {p.fps, p.distance_m, p.facing_deg, p.plantedFootSpeed_mps, p.plantedAnkleSpeed_mps, p.plantedToeSpeed_mps,
        p.jointStep_m, p.jointSpeed_mps})
    CHECK(samples == std::vector<double>{1, 2, 2});
  REQUIRE(p.sides.size() == 3);
  CHECK(p.sides[0].source == "f1");
  CHECK(p.sides[2].source == "f2");
}

TEST_CASE("stats: bodies 20 cm apart interpenetrate every frame", "[stats]") {
  const BoutStats s = measureFolder("overlap");
  CHECK(s.pairFrames == 60);
  CHECK(s.closeFrames == 60);
  CHECK(s.overlapFrames == 60);
  StatsParams tighter;
  tighter.closeDistance_m = 0.1;
  CHECK(measureFolder("overlap", tighter).closeFrames == 0);
}

TEST_CASE("stats: each capture fighter faces the nearest other, simulate's avatars 2k and 2k+1 are partners",
          "[stats]") {
  // Two pairs 5 m apart, 1.0 m and 1.2 m within: half the samples each.
  const BoutStats four = measureFolder("four");
  CHECK(four.fighters == 4);
  CHECK(four.distance_m.size() == 4 * 30);
  CHECK_THAT(median(four.distance_m), WithinAbs(1.1, 1e-9));
  CHECK_THAT(mgrl::quantile(four.distance_m, 1.0), WithinAbs(1.2, 1e-9));
  // avatar_000..003: partners 3 m apart, although avatar 2 stands 1 m from avatar 0.
  const BoutStats partners = measureFolder("partners");
  CHECK_THAT(mgrl::quantile(partners.distance_m, 0.0), WithinAbs(3.0, 1e-9));
  CHECK_THAT(mgrl::quantile(partners.distance_m, 1.0), WithinAbs(3.0, 1e-9));
}

TEST_CASE("stats: the facing samples a reward learns from are the ones stats measures", "[stats]") {
  // learning/real_bouts (the facing term's prefer: bouts) measures facing on its own, below
  // the runtime stage: every sample, in order, as measureBout's, for a walking fighter and
  // for four fighters facing the nearest other.
  for (const char* folder : {"walk", "four", "stand"}) {
    CAPTURE(folder);
    const mgrl::BoutFiles files = mgrl::resolveBout((statsData() / folder).string(), {});
    const std::vector<double> degrees = mgrl::boutFacingDegrees({files});
    const std::vector<double> measured = measureFolder(folder).facing_deg;
    REQUIRE(degrees.size() == measured.size());
    for (std::size_t i = 0; i < degrees.size(); ++i) CHECK_THAT(degrees[i], WithinAbs(measured[i], 1e-9));
  }
  // The walk's fighter 1 steps up to 0.5 m sideways, its opponent 2 m ahead: the largest
  // angle is atan(0.5 / 2) = 14.04 degrees.
  CHECK_THAT(mgrl::quantile(mgrl::boutFacingDegrees({mgrl::resolveBout((statsData() / "walk").string(), {})}), 1.0),
             WithinAbs(std::atan2(0.5, 2.0) * 180 / M_PI, 1e-6));
  // Bad bouts: one clear error each.
  const mgrl::BoutFiles one{"lone", {statsData() / "stand" / "fighter_1.bvh"}};
  REQUIRE_THROWS_WITH(mgrl::boutFacingDegrees({one}),
                      Contains("bout lone: expected at least 2 fighters (BVH files), found 1"));
  const mgrl::BoutFiles mixed = mgrl::resolveBout((statsData() / "mixed_rate").string(), {});
  REQUIRE_THROWS_WITH(mgrl::boutFacingDegrees({mixed}), Contains("expected one frame time for all fighters"));
}

TEST_CASE("stats: a forearm that goes on into the opponent's body is counted, one that stops short is not", "[stats]") {
  // punch_near: fighter 1's left arm (a T-pose arm along X) lunges 40 cm into fighter 2, 1.3 m
  // away: its forearm runs through fighter 2's head and chest capsules for part of the bout.
  const BoutStats near = measureFolder("punch_near");
  CHECK(near.forearmInsideFrames > 0);
  CHECK(near.forearmInsideFrames < near.pairFrames);
  // 3 m away, the same lunge stops short; standing 1 m apart, face to face, with the arms
  // out sideways, and 0.2 m apart (capsules overlapping), no forearm enters the other body.
  CHECK(measureFolder("punch_far").forearmInsideFrames == 0);
  CHECK(measureFolder("stand").forearmInsideFrames == 0);
  CHECK(measureFolder("overlap").forearmInsideFrames == 0);
  // Thinner bodies let fewer frames in.
  StatsParams thin;
  thin.spineRadius_m = thin.chestRadius_m = thin.headRadius_m = 0.01;
  CHECK(measureFolder("punch_near", thin).forearmInsideFrames < near.forearmInsideFrames);
}

TEST_CASE("stats: stances are the medians of equally large parts of the facing samples", "[stats]") {
  // Ten samples, given out of order: parts of 3, 3 and 4 (k n / parts boundaries 0, 3, 6, 10).
  const std::vector<double> samples{90, 10, 30, 20, 100, 40, 50, 60, 80, 70};
  CHECK(mgrl::facingStances(samples, 3) == std::vector<double>{20, 50, 85});
  CHECK(mgrl::facingStances(samples, 1) == std::vector<double>{55});
  CHECK(mgrl::facingStances(samples, 10) == std::vector<double>{10, 20, 30, 40, 50, 60, 70, 80, 90, 100});
  REQUIRE_THROWS_WITH(mgrl::facingStances({1.0, 2.0}, 3),
                      Contains("expected at least as many facing samples as stances (3), found 2"));
  REQUIRE_THROWS_WITH(mgrl::facingStances(samples, 0), Contains("stances (0)"));
}

TEST_CASE("stats: pooling sums counts and times and keeps every sample", "[stats]") {
  const BoutStats a = measureFolder("stand"), b = measureFolder("walk");
  const BoutStats p = mgrl::pool({a, b}, "pooled");
  CHECK(p.bouts == 2);
  CHECK(p.fighters == 4);
  CHECK_THAT(p.fighterSeconds, WithinAbs(a.fighterSeconds + b.fighterSeconds, 1e-12));
  CHECK(p.distance_m.size() == a.distance_m.size() + b.distance_m.size());
  CHECK(p.reversals == 3);
  const nlohmann::json j = mgrl::statsJson(p);
  CHECK(j["fighters"] == 4);
  CHECK(j["distance_m"]["deciles"].size() == 11);
}

TEST_CASE("stats: quantiles interpolate between order statistics", "[stats]") {
  CHECK(mgrl::quantile({3, 1, 2, 4}, 0.5) == 2.5);
  CHECK(mgrl::quantile({3, 1, 2, 4}, 0.0) == 1);
  CHECK(mgrl::quantile({3, 1, 2, 4}, 1.0) == 4);
  CHECK_THAT(mgrl::quantile({0, 10}, 0.25), WithinAbs(2.5, 1e-12));
  CHECK(std::isnan(mgrl::quantile({}, 0.5)));
}

TEST_CASE("stats: Wasserstein-1 of known samples", "[stats]") {
  // A shift moves every unit of mass by the shift.
  CHECK_THAT(mgrl::wasserstein1({0, 1, 2}, {1, 2, 3}), WithinAbs(1.0, 1e-12));
  // {0, 1} against {0.5}: |F_a - F_b| = 1/2 on [0, 1): 0.5.
  CHECK_THAT(mgrl::wasserstein1({0, 1}, {0.5}), WithinAbs(0.5, 1e-12));
  // {0, 0, 3} against {1, 2}: 2/3 on [0, 1), 1/6 on [1, 2), 1/3 on [2, 3) -> 7/6.
  CHECK_THAT(mgrl::wasserstein1({0, 0, 3}, {1, 2}), WithinAbs(7.0 / 6.0, 1e-12));
  CHECK_THAT(mgrl::wasserstein1({2, 5, 1}, {5, 1, 2}), WithinAbs(0.0, 1e-12));
  CHECK(std::isnan(mgrl::wasserstein1({}, {1})));
}

TEST_CASE("stats: segment distances", "[stats]") {
  using V = Eigen::Vector3d;
  CHECK_THAT(mgrl::segmentsDistance(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(1, 1, 0)), WithinAbs(1.0, 1e-12));
  CHECK_THAT(mgrl::segmentsDistance(V(0, 0, 0), V(1, 0, 0), V(0.5, -1, 1), V(0.5, 1, 1)), WithinAbs(1.0, 1e-12));
  CHECK_THAT(mgrl::segmentsDistance(V(0, 0, 0), V(1, 0, 0), V(3, 0, 0), V(4, 0, 0)), WithinAbs(2.0, 1e-12));
  CHECK_THAT(mgrl::segmentsDistance(V(2, 2, 0), V(2, 2, 0), V(0, 0, 0), V(1, 0, 0)), WithinAbs(std::sqrt(5.0), 1e-12));
}

TEST_CASE("stats: bouts of different lengths are cut to the shortest with a warning", "[stats]") {
  std::vector<std::string> warnings;
  const BoutStats s = measureFolder("short", {}, &warnings);
  CHECK(s.frames == 20);
  REQUIRE(warnings.size() == 1);
  CHECK_THAT(warnings[0], Contains("has 30 frames") && Contains("only 20") && Contains("first 20 frames"));
}

TEST_CASE("stats: bad bouts are refused with where, what was expected and what was found", "[stats]") {
  const fs::path data = statsData();
  const StatsParams params;
  auto load = [&](const std::string& argument) {
    const mgrl::BoutFiles files = mgrl::resolveBout(argument, data);
    return mgrl::loadBout(files.name, files.files, params);
  };
  REQUIRE_THROWS_WITH(load("nowhere"), Contains("nowhere: expected a folder of BVH files or a quoted file pattern, "
                                                "found no such folder or file"));
  REQUIRE_THROWS_WITH(load((data / "no_bvh").string()), Contains("no_bvh: expected BVH files in the folder (one per "
                                                                  "fighter), found none"));
  REQUIRE_THROWS_WITH(load("stand/zz_*.bvh"), Contains("stand/zz_*.bvh: expected files matching the pattern, found none"));
  REQUIRE_THROWS_WITH(load("st*nd/fighter_*.bvh"), Contains("expected wildcards only in the file name"));
  REQUIRE_THROWS_WITH(load("stand/fighter_1*.bvh"),
                      Contains("bout fighter_1*.bvh: expected at least 2 fighters (BVH files), found 1"));
  REQUIRE_THROWS_WITH(load("mixed_rate"), Contains("bout mixed_rate: expected one frame time for all fighters, found "
                                                   "0.0333333 s in") &&
                                              Contains("0.0166667 s in"));
  REQUIRE_THROWS_AS(load("broken"), mgrl::ParseError);
  REQUIRE_THROWS_WITH(load("broken"), Contains("fighter_2.bvh:100: expected 6 channel values, found 5"));
  REQUIRE_THROWS_WITH(mgrl::snuBouts(data), Contains("expected the SNU sparring capture s_TTT_K_P.bvh in"));
  // mgrl stats says which of its options asked for them.
  mgrl::StatsOptions snu;
  snu.snu = true;
  snu.dataDir = data;
  REQUIRE_THROWS_WITH(mgrl::runStats(snu), Contains("--snu: expected the SNU sparring capture s_TTT_K_P.bvh in"));
  // Patterns resolve against the data folder (here: tests/data/stats) when not found locally.
  CHECK(mgrl::resolveBout("punch_near/fighter_*.bvh", data).files.size() == 2);
}

TEST_CASE("stats: the real SNU sparring bouts pooled match an earlier measurement loosely", "[stats][data]") {
  const auto groups = mgrl::snuBouts(mgrl::test::mocap());
  // Nine takes-and-clips: eight of two fighters, s_024_2 of four.
  REQUIRE(groups.size() == 9);
  std::size_t fighters = 0;
  for (const auto& g : groups) fighters += g.files.size();
  CHECK(fighters == 20);
  const StatsParams params;
  std::vector<BoutStats> measured;
  for (const auto& g : groups) measured.push_back(mgrl::measureBout(mgrl::loadBout(g.name, g.files, params), params));
  // 408 fighter-seconds at 30 fps (DATA.md).
  CHECK_THAT(mgrl::pool(measured, "pooled").fighterSeconds, WithinAbs(408, 1));
  const BoutStats p = mgrl::pool(measured, "pooled");
  // What the facing term's prefer: bouts learns from: the same samples.
  const std::vector<double>& learned = mgrl::snuFacingDegrees(mgrl::test::mocap());
  CHECK(learned.size() == p.facing_deg.size());
  CHECK_THAT(median(learned), WithinAbs(median(p.facing_deg), 1e-9));
  // The stances prefer: stance learns (scenarios/README.md): thirds about 24, 64 and 126
  // degrees, the middle one the median itself.
  const std::vector<double> thirds = mgrl::facingStances(learned, 3);
  CAPTURE(thirds);
  CHECK_THAT(thirds[1], WithinAbs(median(learned), 1.0));
  CHECK_THAT(thirds[0], WithinAbs(24, 3));
  CHECK_THAT(thirds[2], WithinAbs(126, 3));
  const double minutes = p.fighterSeconds / 60;
  const double strikes = static_cast<double>(p.punches + p.kicks) / minutes;
  const double reversals = static_cast<double>(p.reversals) / static_cast<double>(p.rootSteps);
  CAPTURE(median(p.distance_m), median(p.facing_deg), strikes, median(p.plantedFootSpeed_mps), reversals);
  // An earlier measurement: 1.67 m, 63 deg, 47 strikes per fighter-minute, 0.053 m/s, 1 %; measured here
  // (docs/stats.md): 1.67 m, 64 deg, 45, 0.027 m/s (the slower of ankle and toe), 2.1 %.
  CHECK(median(p.distance_m) > 1.4);
  CHECK(median(p.distance_m) < 1.9);
  CHECK(median(p.facing_deg) > 30);
  CHECK(median(p.facing_deg) < 90);
  CHECK(strikes > 25);
  CHECK(strikes < 90);
  CHECK(median(p.plantedFootSpeed_mps) < 0.12);
  CHECK(reversals < 0.05);
  CHECK(p.closeFrames < p.pairFrames / 100);
}

}  // namespace stats_test
