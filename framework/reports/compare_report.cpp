// The files `mgrl compare --report DIR` writes (compare_report.hpp). The plots are SVG
// drawn here, so the report needs no plotting library and opens from disk.
#include "mgrl/reports/compare_report.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/files.hpp"
#include "mgrl/session/compare_summary.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Three significant digits, no exponent from 0.001 to a million.
std::string plain(double v) {
  const double a = std::abs(v);
  if (a == 0) return "0";
  if (a < 1e-3 || a >= 1e6 || !std::isfinite(v)) return fmt::format("{:.2e}", v);
  // The decimals of the value rounded to three digits (0.9999 -> 1.00, not 1.000).
  const double rounded = std::abs(std::stod(fmt::format("{:.2e}", v)));
  const int decimals = std::max(0, 2 - static_cast<int>(std::floor(std::log10(rounded))));
  return fmt::format("{:.{}f}", v, decimals);
}

// v with an SI prefix for thousands (k, M, G, T) and the unit, three significant digits.
std::string prefixed(double v, std::string_view unit, bool withSpaceForBare) {
  static const char* const prefixes[] = {"", "k", "M", "G", "T"};
  int p = 0;
  while (std::abs(v) >= 999.5 && p < 4) {
    v /= 1000;
    ++p;
  }
  if (p == 0 && std::abs(v - std::round(v)) < 1e-9)
    return fmt::format("{:.0f}{}{}", v, withSpaceForBare ? " " : "", unit);
  return fmt::format("{} {}{}", plain(v), prefixes[p], unit);
}

}  // namespace

std::string reportNumber(std::string_view key, double value, bool delta) {
  if (!std::isfinite(value)) return fmt::format("{}", value);
  if (key == "success_rate" || key == "greedy_agreement" || key == "nonzero_share" || key == "cell_coverage") {
    const double percent = 100 * value;
    return fmt::format("{:.1f}{}", percent, delta ? "" : " %");
  }
  if (key == "mean_time_to_hit_s" || key == "train_seconds" || key == "seconds") {
    // A spread stays in seconds, the unit its mean is read in ("4.26 s" +- "0.0613 s").
    const double a = std::abs(value);
    if (!delta && a != 0 && a < 0.1) return fmt::format("{} ms", plain(value * 1e3));
    return fmt::format("{} s", plain(value));
  }
  if (key == "decision_us")
    return std::abs(value) >= 1000 ? fmt::format("{} ms", plain(value / 1e3)) : fmt::format("{} us", plain(value));
  if (key == "updates") return prefixed(value, "", false);
  if (key == "table_bytes") return prefixed(value, "B", true);
  return plain(value);
}

namespace {

std::string csvField(const json& value) {
  if (value.is_null()) return "";
  if (value.is_string()) return value.get<std::string>();
  return value.dump();
}

std::string escapeHtml(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

const char* const kColours[] = {"#4a7bd0", "#d0584a", "#3a9a4a", "#a04ad0", "#d0a04a", "#4ab0d0"};

// One horizontal bar per learner: the mean over seeds, a whisker for one standard deviation.
std::string barChart(const json& report, const std::string& metric, const std::string& title) {
  const json& learners = report["learners"];
  double top = 0;
  for (const auto& [name, l] : learners.items())
    if (l["mean"][metric].is_number())
      top = std::max(top, l["mean"][metric].get<double>() + l["sd"][metric].get<double>());
  if (top <= 0) top = 1;
  const int rowHeight = 26, left = 150, width = 300;
  const int height = 30 + rowHeight * static_cast<int>(learners.size());
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"{}\">"
      "<text x=\"4\" y=\"16\" font-size=\"13\" font-weight=\"bold\">{}</text>",
      left + width + 90, height, escapeHtml(title), escapeHtml(title));
  int y = 26;
  for (const auto& [name, l] : learners.items()) {
    svg += fmt::format("<text x=\"4\" y=\"{}\" font-size=\"12\">{}</text>", y + 15, escapeHtml(name));
    if (l["mean"][metric].is_number()) {
      const double mean = l["mean"][metric].get<double>(), sd = l["sd"][metric].get<double>();
      const double w = width * mean / top;
      svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{:.1f}\" height=\"18\" fill=\"#4a7bd0\"/>", left, y + 2, w);
      svg +=
          fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{}\" y2=\"{}\" stroke=\"#222\"/>",
                      left + width * std::max(0.0, mean - sd) / top, left + width * (mean + sd) / top, y + 11, y + 11);
      // The value after the bar and its whisker, never across them.
      svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" font-size=\"12\">{}</text>",
                         left + std::max(w, width * (mean + sd) / top) + 6, y + 15,
                         escapeHtml(reportNumber(metric, mean)));
    } else {
      svg += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"12\">n/a</text>", left, y + 15);
    }
    y += rowHeight;
  }
  return svg + "</svg>";
}

// One run's line.
struct Series {
  std::string learner;
  std::vector<std::pair<double, double>> points;
};

// One line per run, coloured by learner, on one plot. x is on a log scale (learners'
// updates and seconds differ by decades: value iteration backs up every pair per sweep);
// y on a log scale (residuals) or linear in [0, 1] (success rates, with a dot per point:
// there are only a few snapshots).
std::string lineChart(const std::string& label, const std::string& title, const std::string& xLabel,
                      const std::vector<Series>& series, bool rate) {
  // The legend sits right of the frame, off the lines.
  const int width = 640, height = 300, left = 60, bottom = 40, top = 20, right = 140;
  double xMin = 1e300, xMax = 0, yMin = rate ? 0 : 1e300, yMax = rate ? 1 : 0;
  for (const Series& s : series)
    for (const auto& [x, y] : s.points) {
      if (x <= 0 || (!rate && y <= 0)) continue;
      xMin = std::min(xMin, x), xMax = std::max(xMax, x);
      if (!rate) yMin = std::min(yMin, y), yMax = std::max(yMax, y);
    }
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"{}\">"
      "<text x=\"4\" y=\"14\" font-size=\"13\" font-weight=\"bold\">{}</text>",
      width, height, escapeHtml(label), escapeHtml(title));
  if (xMax <= 0) return svg + "<text x=\"60\" y=\"150\" font-size=\"12\">no curve points</text></svg>";
  if (xMax <= xMin) xMin = xMax / 10;
  if (yMax <= yMin) yMin = yMax / 10;
  auto px = [&](double x) {
    return left + (width - left - right) * (std::log10(x) - std::log10(xMin)) / (std::log10(xMax) - std::log10(xMin));
  };
  auto py = [&](double y) {
    // Rates keep a little room above 1 and below 0, so a line there stays off the frame.
    const double f = rate ? 0.04 + 0.92 * (y - yMin) / (yMax - yMin)
                          : (std::log10(y) - std::log10(yMin)) / (std::log10(yMax) - std::log10(yMin));
    return height - bottom - (height - top - bottom) * f;
  };
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>", left, top,
                     width - left - right, height - top - bottom);
  // The axis ends in the x quantity's unit (updates: a count, else seconds).
  const std::string xKey = xLabel == "updates" ? "updates" : "seconds";
  svg += fmt::format(
      "<text x=\"{}\" y=\"{}\" font-size=\"11\">{}</text><text x=\"{}\" y=\"{}\" font-size=\"11\" "
      "text-anchor=\"end\">{}</text><text x=\"{}\" y=\"{}\" font-size=\"11\" "
      "text-anchor=\"middle\">{}</text>",
      left, height - bottom + 14, escapeHtml(reportNumber(xKey, xMin)), width - right, height - bottom + 14,
      escapeHtml(reportNumber(xKey, xMax)), (left + width - right) / 2, height - bottom + 28, escapeHtml(xLabel));
  if (rate)
    for (double y : {0.0, 0.5, 1.0})
      svg += fmt::format(
          "<text x=\"4\" y=\"{:.1f}\" font-size=\"11\">{:.0f} %</text><line x1=\"{}\" x2=\"{}\" "
          "y1=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>",
          py(y) + 4, 100 * y, left, width - right, py(y), py(y));
  else
    svg += fmt::format(
        "<text x=\"4\" y=\"{}\" font-size=\"11\">{}</text><text x=\"4\" y=\"{}\" "
        "font-size=\"11\">{}</text>",
        top + 10, plain(yMax), height - bottom, plain(yMin));
  std::map<std::string, int> colourOf;
  int legendY = top + 14;
  for (const Series& s : series) {
    if (!colourOf.count(s.learner)) {
      colourOf[s.learner] = static_cast<int>(colourOf.size()) % 6;
      svg += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"11\" fill=\"{}\">{}</text>", width - right + 10, legendY,
                         kColours[colourOf[s.learner]], escapeHtml(s.learner));
      legendY += 14;
    }
    const char* colour = kColours[colourOf[s.learner]];
    std::string points, dots;
    for (const auto& [x, y] : s.points) {
      if (x <= 0 || (!rate && y <= 0)) continue;
      points += fmt::format("{:.1f},{:.1f} ", px(x), py(y));
      if (rate)
        dots += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>", px(x), py(y), colour);
    }
    svg += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>{}", colour, points,
                       dots);
  }
  return svg + "</svg>";
}

// Every run's points of one kind: the residual curve recorded in training (columns
// updates, seconds, residual, mean residual) or the snapshots (snapshotColumns()).
std::vector<Series> seriesOf(const json& report, bool snapshots, std::size_t x, std::size_t y) {
  std::vector<Series> out;
  for (const json& run : report["runs"]) {
    const json& points =
        snapshots ? (run["snapshots"].is_object() ? run["snapshots"]["points"] : json::array()) : run["curve"];
    Series s{run["learner"].get<std::string>(), {}};
    for (const json& p : points)
      if (p[x].is_number() && p[y].is_number()) s.points.emplace_back(p[x].get<double>(), p[y].get<double>());
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

void writeCompareReport(const fs::path& dir, const json& report) {
  const auto& metrics = compareMetrics();
  writeFileAtomically(dir / "results.json", report.dump(2) + "\n");
  std::string csv = "learner,seed";
  for (const auto& [key, label] : metrics) {
    csv += ',';
    csv += key;
  }
  csv += '\n';
  for (const json& run : report["runs"]) {
    csv += run["learner"].get<std::string>();
    csv += ',';
    csv += csvField(run["seed"]);
    for (const auto& [key, label] : metrics) {
      csv += ',';
      csv += csvField(run[key]);
    }
    csv += '\n';
  }
  writeFileAtomically(dir / "results.csv", csv);

  // Long form: one row per point of a run's training curve ("training") or per snapshot.
  std::string curves =
      "learner,seed,points,updates,seconds,residual,mean_residual,success_rate,mean_time_to_hit_s,mean_return\n";
  for (const json& run : report["runs"]) {
    const std::string who = run["learner"].get<std::string>() + "," + csvField(run["seed"]);
    for (const json& p : run["curve"])
      curves += fmt::format("{},training,{},{},{},{},,,\n", who, csvField(p[0]), csvField(p[1]), csvField(p[2]),
                            csvField(p[3]));
    if (run["snapshots"].is_object())
      for (const json& p : run["snapshots"]["points"])
        curves += fmt::format("{},snapshot,{},{},{},,{},{},{}\n", who, csvField(p[0]), csvField(p[1]), csvField(p[2]),
                              csvField(p[3]), csvField(p[4]), csvField(p[5]));
  }
  writeFileAtomically(dir / "curves.csv", curves);

  const json& reference = report["reference"];
  std::string html = fmt::format(
      "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>mgrl compare: {}</title>"
      "<style>body{{font-family:sans-serif;margin:2em;max-width:80em}}table{{border-collapse:collapse;font-size:90%}}"
      "td,th{{border:1px solid #ccc;padding:2px "
      "6px;text-align:right}}td{{white-space:nowrap}}.sd{{color:#666;font-size:85%}}th:first-child,td:first-child{{"
      "text-align:left}}"
      ".plots{{display:flex;flex-wrap:wrap}}.plots svg{{margin:0.5em 1.5em 0.5em 0}}</style></head><body>\n"
      "<h1>{} on {}: {}</h1>\n<p>Every policy evaluated on the same {} trials; reference: {}. Results: "
      "<a href=\"results.json\">results.json</a>, <a href=\"results.csv\">results.csv</a>, "
      "<a href=\"curves.csv\">curves.csv</a>.</p>\n",
      escapeHtml(report["behavior"].get<std::string>()), escapeHtml(report["behavior"].get<std::string>()),
      escapeHtml(report["scenario_name"].get<std::string>()),
      escapeHtml(fmt::format("{}", fmt::join(report["learner_names"].get<std::vector<std::string>>(), ", "))),
      report["trials"].get<std::size_t>(), escapeHtml(reference["description"].get<std::string>()));
  html += "<table><tr><th>learner</th>";
  for (const auto& [key, label] : metrics) html += "<th>" + escapeHtml(label) + "</th>";
  html += "</tr>\n";
  for (const auto& [name, l] : report["learners"].items()) {
    html += "<tr><td>" + escapeHtml(name) + "</td>";
    for (const auto& [key, label] : metrics)
      html += l["mean"][key].is_number()
                  ? fmt::format("<td>{}<br><span class=\"sd\">&plusmn; {}</span></td>",
                                escapeHtml(reportNumber(key, l["mean"][key].get<double>())),
                                l["sd"][key].get<double>() == 0
                                    ? std::string("0")
                                    : escapeHtml(reportNumber(key, l["sd"][key].get<double>(), true)))
                  : std::string("<td>n/a</td>");
    html += "</tr>\n";
  }
  html += "</table>\n";
  if (!report["flags"].empty()) {
    html += "<h2>Flags</h2><ul>";
    for (const json& flag : report["flags"]) html += "<li>" + escapeHtml(flag.get<std::string>()) + "</li>";
    html += "</ul>\n";
  }
  html += "<h2>Learning curves</h2>\n";
  const std::size_t snapshots = report.value("snapshots", std::size_t{0});
  if (snapshots > 0)
    html += fmt::format(
        "<p>Success rate along training: each run's table taken at about {} evenly spaced points of "
        "its training and evaluated, with the other behaviours as trained, on the first {} of the "
        "same trial starts. Bellman residual: as each learner recorded it (value iteration: the "
        "largest change of a sweep). Training seconds leave the snapshots' evaluation out.</p>\n",
        snapshots, report.value("snapshot_trials", std::size_t{0}));
  html += "<div class=\"plots\">";
  html += lineChart("Success rate against updates", "Success rate against updates (log x)", "updates",
                    seriesOf(report, true, 0, 3), true) +
          "\n";
  html += lineChart("Success rate against training seconds", "Success rate against training seconds (log x)",
                    "training seconds", seriesOf(report, true, 1, 3), true) +
          "\n";
  html += lineChart("Bellman residual against updates", "Bellman residual against updates (log-log)", "updates",
                    seriesOf(report, false, 0, 2), false) +
          "\n";
  html += lineChart("Bellman residual against training seconds", "Bellman residual against training seconds (log-log)",
                    "training seconds", seriesOf(report, false, 1, 2), false) +
          "\n";
  html += "</div>\n<h2>Results per learner</h2>\n<div class=\"plots\">";
  for (const auto& [key, label] : metrics) {
    // A metric no learner has (bundles trained before it was recorded) gets no plot. (The
    // key is captured by name: clang before 16 cannot capture a structured binding.)
    const bool any = std::any_of(report["learners"].begin(), report["learners"].end(),
                                 [&, &name = key](const json& l) { return l["mean"][name].is_number(); });
    if (any) html += barChart(report, key, label) + "\n";
  }
  html += "</div>\n</body></html>\n";
  writeFileAtomically(dir / "index.html", html);
}

}  // namespace mgrl
