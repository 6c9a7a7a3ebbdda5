// `mgrl stats`'s text: the report (mgrl/runtime/bout_report.hpp) as a table, per bout
// or the two groups side by side with their Wasserstein-1 distances.
#include "stats_command.hpp"

#include <cmath>
#include <functional>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "plural.hpp"

namespace mgrl::app {
using nlohmann::json;

namespace {

// "-" for what a bout has none of (a share of nothing, the quantile of no samples).
std::string number(const json& value, const char* format) {
  if (!value.is_number() || !std::isfinite(value.get<double>())) return "-";
  return fmt::format(fmt::runtime(format), value.get<double>());
}

std::string percent(const json& value) {
  if (!value.is_number() || !std::isfinite(value.get<double>())) return "-";
  return fmt::format("{:.1f} %", 100 * value.get<double>());
}

struct Row {
  std::string label;
  std::function<std::string(const json&)> cell;
  const char* w1 = nullptr;  // key of the Wasserstein distance shown beside it, if any
};

std::vector<Row> rows() {
  auto spread = [](const char* key, const char* format) {
    return [key, format](const json& g) {
      return number(g[key]["q1"], format) + " - " + number(g[key]["q3"], format);
    };
  };
  return {
      {"fighters", [](const json& g) { return std::to_string(g["fighters"].get<std::size_t>()); }},
      {"duration (s)", [](const json& g) { return number(g["seconds"], "{:.1f}"); }},
      {"pelvis distance, median (m)", [](const json& g) { return number(g["distance_m"]["median"], "{:.2f}"); },
       "distance_m"},
      {"  quartiles (m)", spread("distance_m", "{:.2f}")},
      {"facing angle, median (deg)", [](const json& g) { return number(g["facing_deg"]["median"], "{:.0f}"); },
       "facing_deg"},
      {"  quartiles (deg)", spread("facing_deg", "{:.0f}")},
      {"strikes / fighter-min", [](const json& g) { return number(g["strikes_per_fighter_minute"], "{:.1f}"); }},
      {"  punches / fighter-min", [](const json& g) { return number(g["punches_per_fighter_minute"], "{:.1f}"); }},
      {"  kicks / fighter-min", [](const json& g) { return number(g["kicks_per_fighter_minute"], "{:.1f}"); }},
      {"landed / fighter-min", [](const json& g) { return number(g["landed_per_fighter_minute"], "{:.1f}"); }},
      {"blocked / fighter-min", [](const json& g) { return number(g["blocked_per_fighter_minute"], "{:.1f}"); }},
      {"blocked or missed (share)", [](const json& g) { return percent(g["unlanded_share"]); }},
      {"landed by the stronger side", [](const json& g) { return percent(g["landed_by_stronger_share"]); }},
      {"planted foot speed, median (m/s)",
       [](const json& g) { return number(g["planted_foot_speed_mps"]["median"], "{:.3f}"); }, "planted_foot_speed_mps"},
      {"  ankles alone, median (m/s)",
       [](const json& g) { return number(g["planted_ankle_speed_mps"]["median"], "{:.3f}"); },
       "planted_ankle_speed_mps"},
      {"  toes alone, median (m/s)",
       [](const json& g) { return number(g["planted_toe_speed_mps"]["median"], "{:.3f}"); }, "planted_toe_speed_mps"},
      {"root reversals per frame", [](const json& g) { return percent(g["reversals_per_frame"]); }},
      {"root reversals per second", [](const json& g) { return number(g["reversals_per_second"], "{:.2f}"); }},
      {"joint step, max (m)", [](const json& g) { return number(g["joint_step_m"]["max"], "{:.3f}"); }},
      {"joint step, 99th pct (m)", [](const json& g) { return number(g["joint_step_m"]["p99"], "{:.3f}"); },
       "joint_step_m"},
      {"joint speed, max (m/s)", [](const json& g) { return number(g["joint_speed_mps"]["max"], "{:.2f}"); }},
      {"joint speed, 99th pct (m/s)", [](const json& g) { return number(g["joint_speed_mps"]["p99"], "{:.2f}"); },
       "joint_speed_mps"},
      {"pelvises closer than limit", [](const json& g) { return percent(g["pelvis_close_share"]); }},
      {"body capsules overlapping", [](const json& g) { return percent(g["capsule_overlap_share"]); }},
      {"forearms inside the opponent", [](const json& g) { return percent(g["forearm_inside_share"]); }},
  };
}

std::string table(const std::vector<std::pair<std::string, const json*>>& columns, const json* w1) {
  const std::vector<Row> all = rows();
  std::size_t labelWidth = 0;
  for (const Row& r : all) labelWidth = std::max(labelWidth, r.label.size());
  std::vector<std::vector<std::string>> cells(all.size());
  std::vector<std::size_t> widths;
  for (const auto& [header, group] : columns) {
    std::size_t width = header.size();
    for (std::size_t r = 0; r < all.size(); ++r) {
      cells[r].push_back(all[r].cell(*group));
      width = std::max(width, cells[r].back().size());
    }
    widths.push_back(width);
  }
  if (w1) {
    std::size_t width = 2;
    for (std::size_t r = 0; r < all.size(); ++r) {
      cells[r].push_back(all[r].w1 ? number((*w1)[all[r].w1], "{:.3f}") : "");
      width = std::max(width, cells[r].back().size());
    }
    widths.push_back(width);
  }
  std::string out = fmt::format("{:<{}}", "", labelWidth);
  for (std::size_t c = 0; c < columns.size(); ++c) out += fmt::format("  {:>{}}", columns[c].first, widths[c]);
  if (w1) out += fmt::format("  {:>{}}", "W1", widths.back());
  out += '\n';
  for (std::size_t r = 0; r < all.size(); ++r) {
    std::string line = fmt::format("{:<{}}", all[r].label, labelWidth);
    for (std::size_t c = 0; c < cells[r].size(); ++c) line += fmt::format("  {:>{}}", cells[r][c], widths[c]);
    line.erase(line.find_last_not_of(' ') + 1);
    out += line + '\n';
  }
  return out;
}

// Strikes each way, one line per bout: "each way, NAME: a.bvh 45 thrown, 20 landed, 12
// blocked | b.bvh ...".
std::string eachWay(const json& bouts) {
  std::string out;
  for (const json& b : bouts) {
    std::vector<std::string> sides;
    for (const json& f : b["by_fighter"])
      sides.push_back(fmt::format("{} {} thrown, {} landed, {} blocked", f["file"].get<std::string>(),
                                  f["strikes"].get<std::size_t>(), f["landed"].get<std::size_t>(),
                                  f["blocked"].get<std::size_t>()));
    out += fmt::format("each way, {}: {}\n", b["name"].get<std::string>(), fmt::join(sides, " | "));
  }
  return out;
}

std::string notes(const json& report) {
  const json& p = report["params"];
  return fmt::format(
      "distance and facing per fighter-frame against the opponent (simulate's partners 2k and 2k+1, "
      "else the nearest fighter); landed: a fist or toe tip within {} m of an opponent's capsule, "
      "unless it came within {} m of a forearm first (blocked); pelvises closer than {} m; "
      "reversals: steps faster than {} m/s (docs/stats.md)\n",
      p["land_radius_m"].get<double>(), p["block_radius_m"].get<double>(), p["close_distance_m"].get<double>(),
      p["reversal_min_speed_mps"].get<double>());
}

}  // namespace

std::string statsText(const json& report) {
  std::string out;
  if (report.contains("wasserstein1")) {
    const json& real = report["real"]["pooled"];
    const json& synthetic = report["synthetic"]["pooled"];
    out += fmt::format("stats: {} real against {} synthesized\n",
                       counted(real["bouts"].get<std::size_t>(), "bout"),
                       counted(synthetic["bouts"].get<std::size_t>(), "bout"));
    out += table({{"real", &real}, {"synthetic", &synthetic}}, &report["wasserstein1"]);
  } else {
    const json& bouts = report["bouts"];
    std::vector<std::pair<std::string, const json*>> columns;
    for (const json& b : bouts) columns.emplace_back(b["name"].get<std::string>(), &b);
    if (bouts.size() > 1) columns.emplace_back("pooled", &report["pooled"]);
    out += fmt::format("stats: {}\n", counted(bouts.size(), "bout"));
    out += table(columns, nullptr);
    out += eachWay(bouts);
  }
  out += notes(report);
  return out;
}

}  // namespace mgrl::app
