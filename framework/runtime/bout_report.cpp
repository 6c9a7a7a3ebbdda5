// Bout reports: resolves bout arguments (folders, patterns, the SNU capture), loads every
// bout before measuring any, and reports per bout, pooled, and two groups side by side
// with Wasserstein-1 distances (`mgrl stats`, docs/stats.md).
#include "mgrl/runtime/bout_report.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/numbers.hpp"

namespace mgrl {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

bool hasWildcard(const std::string& text) { return text.find_first_of("*?[") != std::string::npos; }

bool isBvh(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".bvh";
}

json distribution(const std::vector<double>& samples, int decimals) {
  json deciles = json::array();
  for (int k = 0; k <= 10; ++k) deciles.push_back(rounded(quantile(samples, k / 10.0), decimals));
  return {{"median", rounded(quantile(samples, 0.5), decimals)},
          {"q1", rounded(quantile(samples, 0.25), decimals)},
          {"q3", rounded(quantile(samples, 0.75), decimals)},
          {"deciles", deciles},
          {"samples", samples.size()}};
}

double ratio(double a, double b) { return b > 0 ? a / b : std::numeric_limits<double>::quiet_NaN(); }

std::vector<Bout> loadAll(const std::vector<BoutFiles>& groups, const StatsOptions& options, std::size_t& done,
                          std::size_t total) {
  std::vector<Bout> bouts;
  for (const BoutFiles& group : groups) {
    if (options.log) options.log(fmt::format("stats: loading bout {}/{}: {}", ++done, total, group.name));
    bouts.push_back(loadBout(group.name, group.files, options.params, options.warn));
  }
  return bouts;
}

json groupJson(const std::vector<Bout>& bouts, const StatsParams& params, const std::string& poolName,
               BoutStats& pooled) {
  std::vector<BoutStats> measured;
  json list = json::array();
  for (const Bout& bout : bouts) {
    measured.push_back(measureBout(bout, params));
    json one = statsJson(measured.back());
    one["pairing"] = pairingName(bout.pairing);
    json files = json::array();
    for (const Fighter& f : bout.fighters) files.push_back(f.source);
    one["files"] = files;
    list.push_back(one);
  }
  pooled = pool(measured, poolName);
  return {{"bouts", list}, {"pooled", statsJson(pooled)}};
}

json paramsJson(const StatsParams& p) {
  return {{"land_radius_m", p.landRadius_m},
          {"block_radius_m", p.blockRadius_m},
          {"close_distance_m", p.closeDistance_m},
          {"reversal_min_speed_mps", p.reversalMinSpeed_mps},
          {"capsule_radii_m", {{"spine", p.spineRadius_m}, {"chest", p.chestRadius_m}, {"head", p.headRadius_m}}}};
}

}  // namespace

BoutFiles resolveBout(const std::string& argument, const fs::path& dataDir) {
  if (argument.empty())
    throw Error("stats: expected a BOUT (a folder or a quoted file pattern), found an empty argument");
  fs::path rel(argument);
  if (!rel.has_filename()) rel = rel.parent_path();  // "dir/" names the folder
  const std::string name = rel.filename().string();
  const bool pattern = hasWildcard(name);
  if (hasWildcard(rel.parent_path().string()))
    throw Error(fmt::format("{}: expected wildcards only in the file name, found them in the folder part", argument));
  std::vector<fs::path> bases;
  if (rel.is_absolute())
    bases.emplace_back();
  else
    bases = {fs::path(), dataDir};
  std::error_code ec;
  for (const fs::path& base : bases) {
    const fs::path full = base.empty() ? rel : base / rel;
    if (pattern) {
      const fs::path dir = full.parent_path().empty() ? fs::path(".") : full.parent_path();
      if (!fs::is_directory(dir, ec)) continue;
      std::vector<fs::path> found;
      for (const auto& item : fs::directory_iterator(dir, ec))
        if (item.is_regular_file(ec) && ::fnmatch(name.c_str(), item.path().filename().c_str(), 0) == 0)
          found.push_back(item.path().lexically_normal());
      if (found.empty()) continue;
      std::sort(found.begin(), found.end());
      return {rel.filename().string(), found};
    }
    if (fs::is_directory(full, ec)) {
      std::vector<fs::path> found;
      for (const auto& item : fs::directory_iterator(full, ec))
        if (item.is_regular_file(ec) && isBvh(item.path())) found.push_back(item.path().lexically_normal());
      if (found.empty())
        throw Error(fmt::format("{}: expected BVH files in the folder (one per fighter), found none", full.string()));
      std::sort(found.begin(), found.end());
      return {rel.filename().string(), found};
    }
    if (fs::is_regular_file(full, ec)) return {rel.filename().string(), {full.lexically_normal()}};
  }
  const std::string where =
      rel.is_absolute() ? std::string()
                        : fmt::format(" (looked in the working folder and in the data folder {})", dataDir.string());
  if (pattern) throw Error(fmt::format("{}: expected files matching the pattern, found none{}", argument, where));
  throw Error(
      fmt::format("{}: expected a folder of BVH files or a quoted file pattern, found no such folder or "
                  "file{}",
                  argument, where));
}

namespace {

// Each fighter's strikes: its file's name (the folder is the bout's), counts and rates.
json sidesJson(const std::vector<BoutStats::Side>& sides) {
  json list = json::array();
  for (const BoutStats::Side& side : sides) {
    const double minutes = side.seconds / 60;
    list.push_back({{"file", fs::path(side.source).filename().string()},
                    {"strikes", side.strikes},
                    {"landed", side.landed},
                    {"blocked", side.blocked},
                    {"strikes_per_minute", rounded(ratio(static_cast<double>(side.strikes), minutes), 3)},
                    {"landed_per_minute", rounded(ratio(static_cast<double>(side.landed), minutes), 3)}});
  }
  return list;
}

}  // namespace

json statsJson(const BoutStats& s) {
  const double minutes = s.fighterSeconds / 60;
  const std::size_t strikes = s.punches + s.kicks;
  json fps = json::array();
  for (double f : s.fps) fps.push_back(rounded(f, 4));
  auto largest = [](const std::vector<double>& v) {
    return v.empty() ? std::numeric_limits<double>::quiet_NaN() : *std::max_element(v.begin(), v.end());
  };
  return {
      {"name", s.name},
      {"bouts", s.bouts},
      {"fighters", s.fighters},
      {"frames", s.frames},
      {"fps", fps},
      {"seconds", rounded(s.seconds, 4)},
      {"fighter_minutes", rounded(minutes, 4)},
      {"distance_m", distribution(s.distance_m, 4)},
      {"facing_deg", distribution(s.facing_deg, 2)},
      {"strikes", strikes},
      {"punches", s.punches},
      {"kicks", s.kicks},
      {"landed", s.landed},
      {"strikes_per_fighter_minute", rounded(ratio(static_cast<double>(strikes), minutes), 3)},
      {"punches_per_fighter_minute", rounded(ratio(static_cast<double>(s.punches), minutes), 3)},
      {"kicks_per_fighter_minute", rounded(ratio(static_cast<double>(s.kicks), minutes), 3)},
      {"landed_per_fighter_minute", rounded(ratio(static_cast<double>(s.landed), minutes), 3)},
      {"landed_share", rounded(ratio(static_cast<double>(s.landed), static_cast<double>(strikes)), 4)},
      {"blocked", s.blocked},
      {"blocked_per_fighter_minute", rounded(ratio(static_cast<double>(s.blocked), minutes), 3)},
      {"by_fighter", sidesJson(s.sides)},
      {"landed_by_stronger_share",
       rounded(ratio(static_cast<double>(s.landedByMore), static_cast<double>(s.landedInPairs)), 4)},
      {"unlanded_share",
       rounded(ratio(static_cast<double>(strikes - std::min(s.landed, strikes)), static_cast<double>(strikes)), 4)},
      {"planted_foot_speed_mps", distribution(s.plantedFootSpeed_mps, 4)},
      {"planted_ankle_speed_mps", distribution(s.plantedAnkleSpeed_mps, 4)},
      {"planted_toe_speed_mps", distribution(s.plantedToeSpeed_mps, 4)},
      {"reversals", s.reversals},
      {"reversals_per_frame", rounded(ratio(static_cast<double>(s.reversals), static_cast<double>(s.rootSteps)), 5)},
      {"reversals_per_second", rounded(ratio(static_cast<double>(s.reversals), s.stepSeconds), 4)},
      {"joint_step_m",
       {{"max", rounded(largest(s.jointStep_m), 4)}, {"p99", rounded(quantile(s.jointStep_m, 0.99), 4)}}},
      {"joint_speed_mps",
       {{"max", rounded(largest(s.jointSpeed_mps), 3)}, {"p99", rounded(quantile(s.jointSpeed_mps, 0.99), 3)}}},
      {"pair_frames", s.pairFrames},
      {"pelvis_close_share", rounded(ratio(static_cast<double>(s.closeFrames), static_cast<double>(s.pairFrames)), 5)},
      {"capsule_overlap_share",
       rounded(ratio(static_cast<double>(s.overlapFrames), static_cast<double>(s.pairFrames)), 5)},
      {"forearm_inside_share",
       rounded(ratio(static_cast<double>(s.forearmInsideFrames), static_cast<double>(s.pairFrames)), 5)},
  };
}

json runStats(const StatsOptions& options) {
  options.params.validate();
  std::vector<BoutFiles> real, synthetic;
  if (options.snu) {
    try {
      real = snuBouts(options.dataDir);
    } catch (const Error& e) {
      throw Error(fmt::format("--snu: {}", e.what()));
    }
  }
  for (const std::string& a : options.bouts) real.push_back(resolveBout(a, options.dataDir));
  for (const std::string& a : options.synthetic) synthetic.push_back(resolveBout(a, options.dataDir));
  if (real.empty())
    throw Error(options.compare ? "--compare: expected REAL bouts (or --snu) before '--', found none"
                                : "stats: expected a BOUT (a folder or a quoted file pattern) or --snu, found none");
  if (options.compare && synthetic.empty()) throw Error("--compare: expected synthesized bouts after '--', found none");

  std::size_t done = 0;
  const std::size_t total = real.size() + synthetic.size();
  const std::vector<Bout> realBouts = loadAll(real, options, done, total);
  const std::vector<Bout> syntheticBouts = loadAll(synthetic, options, done, total);
  if (options.log) options.log("stats: measuring");

  json report;
  report["params"] = paramsJson(options.params);
  if (!options.compare) {
    BoutStats pooled;
    const json group = groupJson(realBouts, options.params, "pooled", pooled);
    report["bouts"] = group["bouts"];
    report["pooled"] = group["pooled"];
    return report;
  }
  BoutStats a, b;
  report["real"] = groupJson(realBouts, options.params, "real", a);
  report["synthetic"] = groupJson(syntheticBouts, options.params, "synthetic", b);
  report["wasserstein1"] = {
      {"distance_m", rounded(wasserstein1(a.distance_m, b.distance_m), 4)},
      {"facing_deg", rounded(wasserstein1(a.facing_deg, b.facing_deg), 3)},
      {"planted_foot_speed_mps", rounded(wasserstein1(a.plantedFootSpeed_mps, b.plantedFootSpeed_mps), 4)},
      {"planted_ankle_speed_mps", rounded(wasserstein1(a.plantedAnkleSpeed_mps, b.plantedAnkleSpeed_mps), 4)},
      {"planted_toe_speed_mps", rounded(wasserstein1(a.plantedToeSpeed_mps, b.plantedToeSpeed_mps), 4)},
      {"joint_step_m", rounded(wasserstein1(a.jointStep_m, b.jointStep_m), 5)},
      {"joint_speed_mps", rounded(wasserstein1(a.jointSpeed_mps, b.jointSpeed_mps), 4)},
  };
  return report;
}

}  // namespace mgrl
