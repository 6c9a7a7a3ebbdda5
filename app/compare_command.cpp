// `mgrl compare` (issue 15): learners side by side on one behaviour. The graph is built
// once; the scenario's other behaviours are trained once (with the scenario's learners)
// and shared by every run, so runs differ only in the compared behaviour's learner and
// seed; every policy is evaluated on the same trial starts (one eval seed); tables are
// compared with value iteration's on the same grid, the reference (paper sec. 4.2: both
// solve the same Bellman equation on the grid's vertices).
#include "compare_command.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include <unistd.h>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "learn_common.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "plugins.hpp"
#include "plural.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// A greedy choice that matches the reference's within this much value counts as agreeing
// (ties and float round-off).
constexpr double kAgreementTolerance = 1e-6;
// A run whose greedy policy agrees with the reference on less than this share is flagged.
constexpr double kAgreementFlag = 0.9;

struct Run {
  std::string learner;
  std::uint64_t seed = 0;
  bool seeded = false;               ///< the learner has a seed parameter
  std::vector<std::string> sets;     ///< the scenario's --set plus this run's
  fs::path dir;                      ///< its policy bundle
  std::shared_ptr<const Scenario> scenario;  ///< the scenario with `sets`
};

// The metrics of one run, in the order they are reported.
const std::vector<std::pair<std::string, std::string>> kMetrics = {
    {"success_rate", "success"},     {"mean_time_to_hit_s", "time to hit (s)"},
    {"mean_return", "mean return"},  {"train_seconds", "training (s)"},
    {"updates", "updates"},          {"table_bytes", "table (bytes)"},
    {"decision_us", "decision (us)"}, {"value_rmse", "V RMSE vs reference"},
    {"greedy_agreement", "greedy agreement"}, {"touched_share", "Q entries touched"},
    {"cell_coverage", "grid cells walked"},
};

Scenario loadChecked(const LearnOptions& options, const std::vector<std::string>& sets, const std::string& what) {
  try {
    Scenario scenario = loadScenario(options.scenario, dataDirectory(options.dataDir), sets);
    checkBehaviors(scenario, plugins());
    return scenario;
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", what, e.what()));
  }
}

// V(s, v) = max over s's out-actions of Q: the value the greedy policy acts on.
struct Comparison {
  double rmse = 0, agreement = 0;
};
// Both tables on the same grid; another grid (an adaptive learner's refined tree) has no
// vertex-by-vertex comparison: nullopt.
std::optional<Comparison> compareTables(const QTable& q, const QTable& reference) {
  if (q.vertexCount() != reference.vertexCount() || q.actionCount() != reference.actionCount()) return std::nullopt;
  double squares = 0;
  std::size_t agree = 0, count = 0;
  for (std::size_t s = 0; s < q.stateCount(); ++s) {
    const std::size_t n = q.actionsOf(s);
    if (n == 0) continue;
    for (std::size_t v = 0; v < q.vertexCount(); ++v) {
      const float* row = q.row(s, v);
      const float* ref = reference.row(s, v);
      const std::size_t best = static_cast<std::size_t>(std::max_element(row, row + n) - row);
      const float refBest = *std::max_element(ref, ref + n);
      const double d = static_cast<double>(row[best]) - refBest;
      squares += d * d;
      agree += refBest - ref[best] <= kAgreementTolerance * std::max(1.0f, std::abs(refBest));
      ++count;
    }
  }
  return Comparison{count ? std::sqrt(squares / static_cast<double>(count)) : 0.0,
                    count ? static_cast<double>(agree) / static_cast<double>(count) : 0.0};
}

double touchedShare(const QTable& q) {
  const auto values = q.values();
  const auto touched = std::count_if(values.begin(), values.end(), [](float x) { return x != 0.0f; });
  return values.empty() ? 0.0 : static_cast<double>(touched) / static_cast<double>(values.size());
}

// Copies the shared behaviours' bundle into a run's folder, unless it has a bundle already.
void seedBundle(const fs::path& base, const fs::path& dir) {
  if (fs::exists(dir / "manifest.json")) return;
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directories(dir.parent_path(), ec);
  const fs::path temporary = dir.parent_path() / (dir.filename().string() + ".tmp-copy");
  fs::remove_all(temporary, ec);
  fs::copy(base, temporary, fs::copy_options::recursive, ec);
  if (ec) throw Error(fmt::format("compare: could not copy {} to {}: {}", base.string(), temporary.string(), ec.message()));
  fs::rename(temporary, dir, ec);
  if (ec) throw Error(fmt::format("compare: could not move {} into place: {}", dir.string(), ec.message()));
}

double meanOf(const std::vector<double>& xs) {
  double sum = 0;
  for (double x : xs) sum += x;
  return xs.empty() ? 0 : sum / static_cast<double>(xs.size());
}
double sdOf(const std::vector<double>& xs) {
  if (xs.size() < 2) return 0;
  const double m = meanOf(xs);
  double sum = 0;
  for (double x : xs) sum += (x - m) * (x - m);
  return std::sqrt(sum / static_cast<double>(xs.size() - 1));
}

std::string csvField(const json& value) {
  if (value.is_null()) return "";
  if (value.is_string()) return value.get<std::string>();
  return value.dump();
}

std::string escapeHtml(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

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
      svg += fmt::format("<line x1=\"{:.1f}\" x2=\"{:.1f}\" y1=\"{}\" y2=\"{}\" stroke=\"#222\"/>",
                         left + width * std::max(0.0, mean - sd) / top, left + width * (mean + sd) / top, y + 11, y + 11);
      svg += fmt::format("<text x=\"{:.1f}\" y=\"{}\" font-size=\"12\">{:.4g}</text>", left + w + 6, y + 15, mean);
    } else {
      svg += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"12\">n/a</text>", left, y + 15);
    }
    y += rowHeight;
  }
  return svg + "</svg>";
}

// The Bellman residual against updates, every run, log-log.
std::string residualChart(const json& report) {
  const int width = 520, height = 300, left = 60, bottom = 40, top = 20, right = 20;
  double xMin = 1e300, xMax = 0, yMin = 1e300, yMax = 0;
  for (const json& run : report["runs"])
    for (const json& p : run["curve"]) {
      const double x = p[0].get<double>(), y = p[2].get<double>();
      if (x <= 0 || y <= 0) continue;
      xMin = std::min(xMin, x), xMax = std::max(xMax, x), yMin = std::min(yMin, y), yMax = std::max(yMax, y);
    }
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" role=\"img\" aria-label=\"Bellman "
      "residual against updates\"><text x=\"4\" y=\"14\" font-size=\"13\" font-weight=\"bold\">Bellman residual "
      "against updates (log-log)</text>",
      width, height);
  if (xMax <= 0) return svg + "<text x=\"60\" y=\"150\" font-size=\"12\">no curve points</text></svg>";
  if (xMax <= xMin) xMax = xMin * 10;
  if (yMax <= yMin) yMax = yMin * 10;
  auto px = [&](double x) { return left + (width - left - right) * (std::log10(x) - std::log10(xMin)) / (std::log10(xMax) - std::log10(xMin)); };
  auto py = [&](double y) { return height - bottom - (height - top - bottom) * (std::log10(y) - std::log10(yMin)) / (std::log10(yMax) - std::log10(yMin)); };
  svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>", left, top,
                     width - left - right, height - top - bottom);
  svg += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"11\">{:.3g}</text><text x=\"{}\" y=\"{}\" font-size=\"11\" "
                     "text-anchor=\"end\">{:.3g}</text>",
                     left, height - bottom + 14, xMin, width - right, height - bottom + 14, xMax);
  svg += fmt::format("<text x=\"4\" y=\"{}\" font-size=\"11\">{:.3g}</text><text x=\"4\" y=\"{}\" font-size=\"11\">{:.3g}</text>",
                     top + 10, yMax, height - bottom, yMin);
  const char* colours[] = {"#4a7bd0", "#d0584a", "#3a9a4a", "#a04ad0", "#d0a04a", "#4ab0d0"};
  std::map<std::string, int> colourOf;
  int legendY = top + 14;
  for (const json& run : report["runs"]) {
    const std::string learner = run["learner"].get<std::string>();
    if (!colourOf.count(learner)) {
      colourOf[learner] = static_cast<int>(colourOf.size()) % 6;
      svg += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"11\" fill=\"{}\">{}</text>", width - right - 120, legendY,
                         colours[colourOf[learner]], escapeHtml(learner));
      legendY += 14;
    }
    std::string points;
    for (const json& p : run["curve"]) {
      const double x = p[0].get<double>(), y = p[2].get<double>();
      if (x > 0 && y > 0) points += fmt::format("{:.1f},{:.1f} ", px(x), py(y));
    }
    svg += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>",
                       colours[colourOf[learner]], points);
  }
  return svg + "</svg>";
}

void writeReport(const fs::path& dir, const json& report) {
  writeFileAtomically(dir / "results.json", report.dump(2) + "\n");
  std::string csv = "learner,seed";
  for (const auto& [key, label] : kMetrics) {
    csv += ',';
    csv += key;
  }
  csv += '\n';
  for (const json& run : report["runs"]) {
    csv += run["learner"].get<std::string>();
    csv += ',';
    csv += csvField(run["seed"]);
    for (const auto& [key, label] : kMetrics) {
      csv += ',';
      csv += csvField(run[key]);
    }
    csv += '\n';
  }
  writeFileAtomically(dir / "results.csv", csv);
  std::string html = fmt::format(
      "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>mgrl compare: {}</title>"
      "<style>body{{font-family:sans-serif;margin:2em;max-width:60em}}table{{border-collapse:collapse}}"
      "td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}th:first-child,td:first-child{{text-align:left}}"
      ".plots{{display:flex;flex-wrap:wrap}}.plots svg{{margin:0.5em 1.5em 0.5em 0}}</style></head><body>\n"
      "<h1>{} on {}: {}</h1>\n<p>Every policy evaluated on the same {} trials; reference: value iteration on the "
      "same grid. Results: <a href=\"results.json\">results.json</a>, <a href=\"results.csv\">results.csv</a>.</p>\n",
      escapeHtml(report["behavior"].get<std::string>()), escapeHtml(report["behavior"].get<std::string>()),
      escapeHtml(report["scenario_name"].get<std::string>()),
      escapeHtml(fmt::format("{}", fmt::join(report["learner_names"].get<std::vector<std::string>>(), ", "))),
      report["trials"].get<std::size_t>());
  html += "<table><tr><th>learner</th>";
  for (const auto& [key, label] : kMetrics) html += "<th>" + escapeHtml(label) + "</th>";
  html += "</tr>\n";
  for (const auto& [name, l] : report["learners"].items()) {
    html += "<tr><td>" + escapeHtml(name) + "</td>";
    for (const auto& [key, label] : kMetrics)
      html += l["mean"][key].is_number()
                  ? fmt::format("<td>{:.4g} &plusmn; {:.2g}</td>", l["mean"][key].get<double>(), l["sd"][key].get<double>())
                  : std::string("<td>n/a</td>");
    html += "</tr>\n";
  }
  html += "</table>\n";
  if (!report["flags"].empty()) {
    html += "<h2>Flags</h2><ul>";
    for (const json& flag : report["flags"]) html += "<li>" + escapeHtml(flag.get<std::string>()) + "</li>";
    html += "</ul>\n";
  }
  html += "<div class=\"plots\">";
  for (const auto& [key, label] : kMetrics) {
    // A metric no learner has (bundles trained before it was recorded) gets no plot.
    const bool any = std::any_of(report["learners"].begin(), report["learners"].end(),
                                 [&](const json& l) { return l["mean"][key].is_number(); });
    if (any) html += barChart(report, key, label) + "\n";
  }
  html += residualChart(report) + "</div>\n</body></html>\n";
  writeFileAtomically(dir / "index.html", html);
}

}  // namespace

json runCompare(const CompareOptions& options) {
  // Every mistake in the options, before anything is trained.
  if (options.learners.empty()) throw Error("--learners: expected a comma-separated list of learners, found none");
  std::set<std::string> seen;
  for (const std::string& learner : options.learners) {
    if (!plugins().learners.find(learner)) {
      std::vector<std::string> known;
      for (const auto& entry : plugins().learners.entries()) known.push_back(entry.name);
      throw Error(fmt::format("--learners: expected registered learners ({}), found {}", fmt::join(known, ", "),
                              quoteToken(learner)));
    }
    if (!seen.insert(learner).second)
      throw Error(fmt::format("--learners: expected each learner once, found {} twice", quoteToken(learner)));
  }
  if (options.seeds.empty()) throw Error("--seeds: expected a comma-separated list of seeds, found none");
  if (std::set<std::uint64_t>(options.seeds.begin(), options.seeds.end()).size() != options.seeds.size())
    throw Error(fmt::format("--seeds: expected each seed once, found {}", fmt::join(options.seeds, ",")));
  if (options.trials < 1 || options.trials > 100000)
    throw Error(fmt::format("--trials: expected a number of trials in [1, 100000], found {}", options.trials));
  std::map<std::string, std::vector<std::string>> learnerSets;
  for (const std::string& set : options.learnerSets) {
    const auto colon = set.find(':'), eq = set.find('=');
    if (colon == std::string::npos || colon == 0 || eq == std::string::npos || eq < colon + 2)
      throw Error(fmt::format("--learner-set: expected LEARNER:KEY=VALUE, found {}", quoteToken(set)));
    const std::string learner = set.substr(0, colon);
    if (!seen.count(learner))
      throw Error(fmt::format("--learner-set {}: expected a learner from --learners ({}), found {}", set,
                              fmt::join(options.learners, ", "), quoteToken(learner)));
    learnerSets[learner].push_back(fmt::format("behaviors.{}.learner.{}", options.behavior, set.substr(colon + 1)));
  }

  Scenario scenario = checkedScenario(options);
  requireBehavior(scenario, options.behavior);
  std::vector<std::string> names;
  for (const BehaviorSpec& spec : scenario.behaviors) names.push_back(spec.name);

  const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  const fs::path compareCache = cacheDir / "compare";
  std::vector<Run> runs;
  auto runSets = [&](const std::string& learner) {
    std::vector<std::string> sets = options.sets;
    sets.push_back(fmt::format("behaviors.{}.learner.type={}", options.behavior, learner));
    for (const std::string& s : learnerSets[learner]) sets.push_back(s);
    return sets;
  };
  for (const std::string& learner : options.learners) {
    const ParamSpecs& params = plugins().learners.find(learner)->params;
    const bool seeded = std::any_of(params.begin(), params.end(), [](const ParamSpec& p) { return p.name == "seed"; });
    // A learner with no seed is deterministic: one run stands for every seed.
    for (std::size_t k = 0; k < (seeded ? options.seeds.size() : 1); ++k) {
      Run run{learner, seeded ? options.seeds[k] : 0, seeded, runSets(learner), {}, nullptr};
      if (seeded) run.sets.push_back(fmt::format("behaviors.{}.learner.seed={}", options.behavior, run.seed));
      const Scenario checked = loadChecked(options, run.sets, fmt::format("--learners {}", learner));
      run.dir = defaultPolicyDirectory(compareCache, checked);
      run.scenario = std::make_shared<Scenario>(checked);
      runs.push_back(std::move(run));
    }
  }
  // The reference: value iteration on the behaviour's grid.
  Run reference{"value_iteration", 0, false, runSets("value_iteration"), {}, nullptr};
  if (learnerSets.count("value_iteration") == 0) {
    reference.sets = options.sets;
    reference.sets.push_back(fmt::format("behaviors.{}.learner.type=value_iteration", options.behavior));
  }
  reference.scenario = std::make_shared<Scenario>(loadChecked(options, reference.sets, "reference"));
  reference.dir = defaultPolicyDirectory(compareCache, *reference.scenario);
  if (!options.report.empty()) {
    std::error_code ec;
    fs::create_directories(options.report, ec);
    const fs::path probe = options.report / fmt::format(".mgrl-probe-{}", ::getpid());
    std::ofstream out(probe);
    if (ec || !(out << "x") || !out.flush())
      throw Error(fmt::format("--report {}: expected a folder where files can be written, found {}",
                              options.report.string(), ec ? ec.message() : std::string("it cannot be written")));
    out.close();
    fs::remove(probe, ec);
  }

  auto log = [&](const std::string& line) {
    if (options.log) options.log(line);
  };
  // The graph first (cached after the first time): every learner is checked against its
  // grid before anything is trained.
  const fs::path base = compareCache / fmt::format("{}-shared", defaultPolicyDirectory(compareCache, scenario).filename().string());
  Loaded loaded = load(options, std::move(scenario));
  const StateActionModel& model = loaded.graph.model;
  for (const Run* run : [&] {
         std::vector<const Run*> all{&reference};
         for (const Run& r : runs) all.push_back(&r);
         return all;
       }()) {
    for (const Behavior& b : buildBehaviors(*run->scenario, plugins(), model, loaded.graph.key))
      if (b.name == options.behavior) {
        try {
          b.learner->checkGrid(*b.discretizer);
        } catch (const Error& e) {
          throw Error(fmt::format("--learners {}: behaviors.{}: {}", run->learner, b.name, e.what()));
        }
      }
  }

  // The shared behaviours, trained once with the scenario's settings.
  for (const std::string& name : names) {
    if (name == options.behavior) continue;
    TrainOptions train;
    static_cast<LearnOptions&>(train) = options;
    train.behavior = name;
    train.out = base;
    train.resume = true;  // kept when already trained with the same settings
    log(fmt::format("compare: {} (shared by every run)", name));
    runTrain(train);
  }

  auto trainRun = [&](const Run& run, const std::string& label) {
    if (names.size() > 1) seedBundle(base, run.dir);
    TrainOptions train;
    static_cast<LearnOptions&>(train) = options;
    train.sets = run.sets;
    train.behavior = options.behavior;
    train.out = run.dir;
    train.resume = true;
    log(fmt::format("compare: {}", label));
    runTrain(train);
  };
  trainRun(reference, "reference: value_iteration");
  const QTable referenceTable =
      std::move(loadPolicyBundle(reference.dir, model, loaded.graph.key).behaviors.at(options.behavior).table);

  json report = {{"scenario", loaded.scenario.path.string()},
                 {"scenario_name", loaded.scenario.name},
                 {"behavior", options.behavior},
                 {"learner_names", options.learners},
                 {"seeds", options.seeds},
                 {"trials", options.trials},
                 {"seconds_per_trial", options.seconds},
                 {"reference", {{"learner", "value_iteration"}, {"policy", reference.dir.string()}}},
                 {"runs", json::array()},
                 {"learners", json::object()},
                 {"flags", json::array()}};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Run& run = runs[i];
    const std::string label = run.seeded ? fmt::format("{} seed {}", run.learner, run.seed) : run.learner;
    trainRun(run, fmt::format("[{}/{}] {}", i + 1, runs.size(), label));
    EvalOptions eval;
    static_cast<LearnOptions&>(eval) = options;
    eval.sets = run.sets;
    eval.policy = run.dir;
    eval.trials = options.trials;
    eval.seconds = options.seconds;
    eval.seed = 1;  // the same trial starts for every run
    const json evaluated = runEval(eval);
    PolicyBundle bundle = loadPolicyBundle(run.dir, model, loaded.graph.key);
    const PolicyBehavior& trained = bundle.behaviors.at(options.behavior);
    const std::optional<Comparison> c = compareTables(trained.table, referenceTable);
    const double perSecond = evaluated["decisions_per_second"].get<double>();
    json r = {{"learner", run.learner},
              {"seed", run.seeded ? json(run.seed) : json(nullptr)},
              {"policy", run.dir.string()},
              {"success_rate", evaluated["success_rate"]},
              {"mean_time_to_hit_s", evaluated["mean_time_to_hit_s"]},
              {"mean_return", evaluated["mean_return"]},
              {"train_seconds", trained.record.value("seconds", 0.0)},
              {"updates", trained.record.value("updates", std::uint64_t{0})},
              {"table_bytes", trained.table.bytes()},
              {"final_residual", trained.record.value("final_residual", 0.0)},
              {"decision_us", perSecond > 0 ? 1e6 / perSecond : 0.0},
              {"value_rmse", c ? json(c->rmse) : json()},
              {"greedy_agreement", c ? json(c->agreement) : json()},
              {"touched_share", touchedShare(trained.table)},
              {"cell_coverage", trained.record.contains("stats") ? trained.record["stats"].value("cell_coverage", json())
                                                                 : json()},
              {"curve", trained.record.value("curve", json::array())}};
    if (!c)
      report["flags"].push_back(fmt::format("{}: its table is on another grid ({} vertices, the reference's {}): no "
                                            "value comparison",
                                            label, trained.table.vertexCount(), referenceTable.vertexCount()));
    else if (c->agreement < kAgreementFlag)
      report["flags"].push_back(fmt::format(
          "{}: its greedy policy agrees with the reference's on {:.1f} % of (state, vertex) pairs (value RMSE {:.3g}; "
          "{:.1f} % of its Q entries were ever updated)",
          label, 100 * c->agreement, c->rmse, 100 * r["touched_share"].get<double>()));
    report["runs"].push_back(r);
  }
  for (const std::string& learner : options.learners) {
    json mean = json::object(), sd = json::object();
    for (const auto& [key, label] : kMetrics) {
      std::vector<double> xs;
      bool missing = false;
      for (const json& r : report["runs"])
        if (r["learner"] == learner) {
          if (r[key].is_number())
            xs.push_back(r[key].get<double>());
          else
            missing = true;
        }
      mean[key] = missing || xs.empty() ? json(nullptr) : json(meanOf(xs));
      sd[key] = missing || xs.empty() ? json(nullptr) : json(sdOf(xs));
    }
    report["learners"][learner] = {{"mean", mean}, {"sd", sd}};
  }
  if (!options.report.empty()) {
    writeReport(options.report, report);
    report["report"] = (options.report / "index.html").string();
  }
  return report;
}

std::string compareText(const json& r) {
  std::string text = fmt::format("compare {} on {}: {}, {} trials each on the same starts; reference: value "
                                 "iteration on the same grid\n",
                                 r["behavior"].get<std::string>(), r["scenario_name"].get<std::string>(),
                                 counted(r["runs"].size(), "run"), r["trials"].get<std::size_t>());
  text += fmt::format("{:<24} {:>14} {:>13} {:>13} {:>12} {:>10} {:>11} {:>11} {:>10}\n", "learner (mean ± sd)",
                      "success %", "time to hit s", "train s", "updates", "decide us", "V RMSE", "agreement %",
                      "touched %");
  auto cell = [](const json& l, const char* key, double scale, const char* format) {
    if (!l["mean"][key].is_number()) return std::string("n/a");
    return fmt::format(fmt::runtime(format), scale * l["mean"][key].get<double>(), scale * l["sd"][key].get<double>());
  };
  for (const auto& [name, l] : r["learners"].items())
    text += fmt::format("{:<24} {:>14} {:>13} {:>13} {:>12} {:>10} {:>11} {:>11} {:>10}\n", name,
                        cell(l, "success_rate", 100, "{:.1f} ± {:.1f}"), cell(l, "mean_time_to_hit_s", 1, "{:.2f} ± {:.2f}"),
                        cell(l, "train_seconds", 1, "{:.2f} ± {:.2f}"), cell(l, "updates", 1e-6, "{:.1f}M"),
                        cell(l, "decision_us", 1, "{:.2f}"), cell(l, "value_rmse", 1, "{:.3g}"),
                        cell(l, "greedy_agreement", 100, "{:.1f}"), cell(l, "touched_share", 100, "{:.1f}"));
  for (const json& flag : r["flags"]) text += "flag: " + flag.get<std::string>() + "\n";
  if (r.contains("report")) text += fmt::format("report: {}\n", r["report"].get<std::string>());
  return text;
}

}  // namespace mgrl::app
