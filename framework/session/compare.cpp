// Comparing learners (`mgrl compare`): learners side by side on one behaviour. The graph is built
// once; the scenario's other behaviours are trained once (with the scenario's learners)
// and shared by every run, so runs differ only in the compared behaviour's learner and
// seed; every policy is evaluated on the same trial starts (one eval seed), and so are
// snapshots of it along training (learning curves of success rate); tables are compared
// with the reference, value iteration on the same grid (paper sec. 4.2: both solve the
// same Bellman equation on the grid's vertices) or on a finer one (--reference-set).
//
// The report's page is compare_report.cpp, the learning-curve snapshots compare_snapshots.cpp,
// the tables' comparison compare_tables.cpp.
#include "mgrl/session/compare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/compare_snapshots.hpp"
#include "mgrl/session/compare_summary.hpp"
#include "mgrl/session/compare_tables.hpp"
#include "mgrl/session/evaluate.hpp"
#include "mgrl/session/session.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// A run whose greedy policy agrees with the reference on less than this share is flagged.
constexpr double kAgreementFlag = 0.9;

struct Run {
  std::string learner;
  std::uint64_t seed = 0;
  bool seeded = false;                       ///< the learner has a seed parameter
  std::vector<std::string> sets;             ///< the scenario's --set plus this run's
  fs::path dir;                              ///< its policy bundle
  std::shared_ptr<const Scenario> scenario;  ///< the scenario with `sets`
};

Scenario loadChecked(const CompareOptions& options, const std::vector<std::string>& sets, const std::string& what) {
  try {
    Scenario scenario = loadScenario(options.scenario, dataDirectory(options.dataDir), sets);
    checkBehaviors(scenario, requirePlugins(options.plugins, "CompareOptions::plugins"));
    return scenario;
  } catch (const Error& e) {
    throw Error(fmt::format("{}: {}", what, e.what()));
  }
}

// The share of Q entries that are not zero. Not a count of updates: an entry backed up to
// 0 (no reward within reach) stays 0, so value iteration, which updates every entry each
// sweep, has zeros too; the walk's reach is q_learning's cell_coverage.
double nonzeroShare(const QTable& q) {
  const auto values = q.values();
  const auto nonzero = std::count_if(values.begin(), values.end(), [](float x) { return x != 0.0f; });
  return values.empty() ? 0.0 : static_cast<double>(nonzero) / static_cast<double>(values.size());
}

// A figure of a trained behaviour's record, null when the record lacks it (a bundle written
// before it was recorded, or by another writer): reported as missing, never as a measured 0.
json recorded(const json& record, const char* key) {
  const auto it = record.find(key);
  return it != record.end() && it->is_number() ? *it : json(nullptr);
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
  if (ec)
    throw Error(fmt::format("compare: could not copy {} to {}: {}", base.string(), temporary.string(), ec.message()));
  fs::rename(temporary, dir, ec);
  if (ec) throw Error(fmt::format("compare: could not move {} into place: {}", dir.string(), ec.message()));
}

}  // namespace

// One run's row of the report: its evaluation, training record and comparison with the
// reference's table.
json runJson(const Run& run, const PolicyBehavior& trained, const json& evaluated, const Comparison& c,
             bool snapshots) {
  const double perSecond = evaluated["decisions_per_second"].get<double>();
  json r = {{"learner", run.learner},
            {"seed", run.seeded ? json(run.seed) : json(nullptr)},
            {"policy", run.dir.string()},
            {"success_rate", evaluated["success_rate"]},
            {"mean_time_to_hit_s", evaluated["mean_time_to_hit_s"]},
            {"mean_return", evaluated["mean_return"]},
            {"train_seconds", recorded(trained.record, "seconds")},
            {"updates", recorded(trained.record, "updates")},
            {"table_bytes", trained.table.bytes()},
            {"final_residual", recorded(trained.record, "final_residual")},
            {"decision_us", perSecond > 0 ? json(1e6 / perSecond) : json(nullptr)},
            {"value_rmse", c.rmse},
            {"greedy_agreement", c.agreement},
            {"reference_interpolated", c.interpolated},
            {"nonzero_share", nonzeroShare(trained.table)},
            {"cell_coverage",
             trained.record.contains("stats") ? trained.record["stats"].value("cell_coverage", json()) : json()},
            {"curve", trained.record.value("curve", json::array())},
            {"snapshots", json(nullptr)}};
  if (trained.record.contains("snapshots") && snapshots) {
    const json& taken = trained.record["snapshots"];
    r["snapshots"] = {{"columns", taken["columns"]}, {"points", taken["points"]}};
  }
  return r;
}

// Every mistake in the options, before anything is trained: the --learner-set and
// --reference-set flags as --set keys, and the snapshot trials.
struct CheckedFlags {
  std::map<std::string, std::vector<std::string>> learnerSets;
  std::vector<std::string> referenceSets;
  std::size_t snapshotTrials = 0;
};

CheckedFlags checkFlags(const CompareOptions& options) {
  if (options.learners.empty()) throw Error("--learners: expected a comma-separated list of learners, found none");
  std::set<std::string> seen;
  for (const std::string& learner : options.learners) {
    if (!requirePlugins(options.plugins, "CompareOptions::plugins").learners.find(learner))
      throw Error(fmt::format("--learners: expected registered learners ({}), found {}",
                              requirePlugins(options.plugins, "CompareOptions::plugins").learners.describeKnown(),
                              quoteToken(learner)));
    if (!seen.insert(learner).second)
      throw Error(fmt::format("--learners: expected each learner once, found {} twice", quoteToken(learner)));
  }
  if (options.seeds.empty()) throw Error("--seeds: expected a comma-separated list of seeds, found none");
  if (std::set<std::uint64_t>(options.seeds.begin(), options.seeds.end()).size() != options.seeds.size())
    throw Error(fmt::format("--seeds: expected each seed once, found {}", fmt::join(options.seeds, ",")));
  if (options.trials < 1 || options.trials > 100000)
    throw Error(fmt::format("--trials: expected a number of trials in [1, 100000], found {}", options.trials));
  CheckedFlags flags;
  auto& learnerSets = flags.learnerSets;
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
  if (options.snapshots > 1000)
    throw Error(
        fmt::format("--snapshots: expected a number of snapshots per run in [0, 1000], found {}", options.snapshots));
  const std::size_t snapshotTrials = flags.snapshotTrials =
      options.snapshotTrials > 0 ? options.snapshotTrials : std::min(kDefaultSnapshotTrials, options.trials);
  if (snapshotTrials > options.trials)
    throw Error(
        fmt::format("--snapshot-trials: expected at most --trials ({}): snapshots are evaluated on the first "
                    "of the same trial starts, found {}",
                    options.trials, snapshotTrials));
  auto& referenceSets = flags.referenceSets;
  for (const std::string& set : options.referenceSets) {
    const auto eq = set.find('=');
    if (eq == std::string::npos || eq == 0 || set.find('.') < eq)
      throw Error(
          fmt::format("--reference-set: expected KEY=VALUE, KEY a parameter of behaviors.{}.discretizer "
                      "(e.g. angles=40), found {}",
                      options.behavior, quoteToken(set)));
    referenceSets.push_back(fmt::format("behaviors.{}.discretizer.{}", options.behavior, set));
  }
  return flags;
}

// The --set keys of a run of `learner`: the scenario's, the learner, its --learner-set's.
std::vector<std::string> runSets(const CompareOptions& options,
                                 std::map<std::string, std::vector<std::string>>& learnerSets,
                                 const std::string& learner) {
  std::vector<std::string> sets = options.sets;
  sets.push_back(fmt::format("behaviors.{}.learner.type={}", options.behavior, learner));
  for (const std::string& s : learnerSets[learner]) sets.push_back(s);
  return sets;
}

// The runs of the comparison: each learner once per seed (once if it has no seed), with
// its --learner-set keys, and where its bundle goes.
std::vector<Run> planRuns(const CompareOptions& options, std::map<std::string, std::vector<std::string>>& learnerSets,
                          const fs::path& compareCache) {
  std::vector<Run> runs;
  for (const std::string& learner : options.learners) {
    const ParamSpecs& params =
        requirePlugins(options.plugins, "CompareOptions::plugins").learners.find(learner)->params;
    const bool seeded = std::any_of(params.begin(), params.end(), [](const ParamSpec& p) { return p.name == "seed"; });
    // A learner with no seed is deterministic: one run stands for every seed.
    for (std::size_t k = 0; k < (seeded ? options.seeds.size() : 1); ++k) {
      Run run{learner, seeded ? options.seeds[k] : 0, seeded, runSets(options, learnerSets, learner), {}, nullptr};
      if (seeded) run.sets.push_back(fmt::format("behaviors.{}.learner.seed={}", options.behavior, run.seed));
      const Scenario checked = loadChecked(options, run.sets, fmt::format("--learners {}", learner));
      run.dir = defaultPolicyDirectory(compareCache, checked, *options.plugins);
      run.scenario = std::make_shared<Scenario>(checked);
      runs.push_back(std::move(run));
    }
  }
  return runs;
}

// The reference: value iteration on the behaviour's grid, or on the grid --reference-set
// asks for.
Run planReference(const CompareOptions& options, CheckedFlags& flags, const fs::path& compareCache) {
  Run reference{"value_iteration", 0, false, runSets(options, flags.learnerSets, "value_iteration"), {}, nullptr};
  if (flags.learnerSets.count("value_iteration") == 0) {
    reference.sets = options.sets;
    reference.sets.push_back(fmt::format("behaviors.{}.learner.type=value_iteration", options.behavior));
  }
  reference.sets.insert(reference.sets.end(), flags.referenceSets.begin(), flags.referenceSets.end());
  reference.scenario = std::make_shared<Scenario>(
      loadChecked(options, reference.sets, flags.referenceSets.empty() ? "reference" : "--reference-set"));
  reference.dir = defaultPolicyDirectory(compareCache, *reference.scenario, *options.plugins);
  return reference;
}

// Every run's grid checked before anything is trained (and, with --reference-set, covered
// by the reference's); returns the behaviour's grid size.
std::size_t checkRunGrids(const CompareOptions& options, const std::vector<Run>& runs, const Discretizer& referenceGrid,
                          bool referenceSet, const StateActionModel& model, const std::string& graphKey) {
  std::size_t behaviorVertices = 0;
  for (const Run& run : runs) {
    for (const Behavior& b : buildBehaviors(*run.scenario, *options.plugins, model, graphKey))
      if (b.name == options.behavior) {
        try {
          b.learner->checkGrid(*b.discretizer);
        } catch (const Error& e) {
          throw Error(fmt::format("--learners {}: behaviors.{}: {}", run.learner, b.name, e.what()));
        }
        if (referenceSet) requireCovers(referenceGrid, *b.discretizer, b.name);
        behaviorVertices = b.discretizer->vertexCount();
      }
  }
  return behaviorVertices;
}

// Trains the behaviour `settings.behavior` of the scenario with `sets`, as `mgrl train`
// does: a session of its own (the model only; the graph shared with `graph`'s when the
// same), trainScenario() with the caller's hooks.
void trainWithSets(const CompareOptions& options, const std::vector<std::string>& sets, const TrainSettings& settings,
                   const TrainHooks& hooks, const GraphResult& graph) {
  SessionOptions session = options;
  session.sets = sets;
  SessionNeeds needs;
  needs.motion = false;
  needs.graphFrom = &graph;
  const std::unique_ptr<const Session> opened = openSession(session, needs);
  TrainHooks quiet = hooks;
  quiet.log = options.log;
  trainScenario(*opened, settings, quiet);
}

// Trains one run (resuming its cached bundle), the shared behaviours seeded from `base`.
// A run with snapshots wanted and a cached bundle without them (trained before they were
// recorded, or with other --snapshots, --snapshot-trials or --seconds) is trained again:
// the same table, now with its learning curve.
void trainCompareRun(const CompareOptions& options, const Run& run, const std::string& label, bool snapshots,
                     const fs::path& base, bool shared, std::size_t snapshotTrials, const TrainHooks& given,
                     const GraphResult& graph) {
  if (shared) seedBundle(base, run.dir);
  TrainSettings train;
  train.behavior = options.behavior;
  train.out = run.dir;
  train.resume = true;
  TrainHooks hooks = given;
  if (options.log) options.log(fmt::format("compare: {}", label));
  if (snapshots) {
    if (lacksSnapshots(run.dir, options.behavior, options.snapshots, snapshotTrials, options.seconds)) {
      if (options.log)
        options.log(fmt::format(
            "compare: {}: the cached bundle has no snapshots taken with these settings; training again to take them",
            label));
      train.resume = false;
    }
    hooks.listen = [&options, base, snapshotTrials](const Behavior& trained, const std::vector<Behavior>& all,
                                                    const GraphResult& trainedGraph) {
      return std::make_unique<SnapshotEvaluator>(trained, all, trainedGraph, base, options, options.snapshots,
                                                 snapshotTrials);
    };
  }
  trainWithSets(options, run.sets, train, hooks, graph);
}

// `mgrl eval`'s report of the bundle at `dir` (trained with `sets`): the policy, greedy, on
// `trials` of `seconds` from eval seed 1, the same starts for every run.
json evaluateRun(const CompareOptions& options, const std::vector<std::string>& sets, const fs::path& dir,
                 const GraphResult& graph) {
  SessionOptions session = options;
  session.sets = sets;
  SessionNeeds needs;
  needs.policy = PolicyNeed::Required;
  needs.policyDir = dir;
  needs.motion = false;  // trials need no poses
  needs.graphFrom = &graph;
  const std::unique_ptr<const Session> opened = openSession(session, needs);
  EvalSettings settings;
  settings.trials = options.trials;
  settings.seconds = options.seconds;
  settings.seed = 1;
  checkEvalSettings(opened->plugins().controllers, settings);
  return evaluate(*opened, opened->policy, settings);
}

// The report's "reference" entry: what it is, where its bundle is, how long it trained.
json referenceReport(const CompareOptions& options, const Run& reference, const PolicyBehavior& referenceTrained,
                     const Discretizer& referenceGrid, std::size_t behaviorVertices) {
  json out = {{"learner", "value_iteration"},  {"policy", reference.dir.string()},
              {"grid", referenceGrid.type()},  {"vertices", referenceGrid.vertexCount()},
              {"sets", options.referenceSets}, {"train_seconds", recorded(referenceTrained.record, "seconds")}};
  out["description"] = options.referenceSets.empty()
                           ? fmt::format("value iteration on the behaviour's grid ({}, {} vertices)",
                                         referenceGrid.type(), referenceGrid.vertexCount())
                           : fmt::format(
                                 "value iteration on a grid set by --reference-set {} ({}, {} vertices against the "
                                 "behaviour's {}), interpolated at each table's vertices",
                                 fmt::join(options.referenceSets, " "), referenceGrid.type(),
                                 referenceGrid.vertexCount(), behaviorVertices);
  return out;
}

json compareLearners(const CompareOptions& options, const TrainHooks& hooks) {
  CheckedFlags flags = checkFlags(options);
  auto& learnerSets = flags.learnerSets;
  const auto& referenceSets = flags.referenceSets;
  const std::size_t snapshotTrials = flags.snapshotTrials;

  Scenario scenario = checkedScenario(options);
  requireBehavior(scenario, options.behavior);
  std::vector<std::string> names;
  for (const BehaviorSpec& spec : scenario.behaviors) names.push_back(spec.name);

  const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  const fs::path compareCache = cacheDir / "compare";
  std::vector<Run> runs = planRuns(options, learnerSets, compareCache);
  const Run reference = planReference(options, flags, compareCache);

  auto log = [&](const std::string& line) {
    if (options.log) options.log(line);
  };
  // The graph first (cached after the first time): every learner is checked against its
  // grid before anything is trained.
  const fs::path base =
      compareCache /
      fmt::format("{}-shared", defaultPolicyDirectory(compareCache, scenario, *options.plugins).filename().string());
  SessionNeeds needs;
  needs.motion = false;  // the model is enough: no poses
  const std::unique_ptr<const Session> opened = openSession(options, needs);
  const GraphResult& graph = opened->graph;
  const StateActionModel& model = graph.model;
  // The reference's grid stays: tables on other grids are measured by interpolating on it.
  const std::vector<Behavior> referenceBehaviors =
      buildBehaviors(*reference.scenario, *options.plugins, model, graph.key);
  const Behavior& referenceBehavior = *std::find_if(referenceBehaviors.begin(), referenceBehaviors.end(),
                                                    [&](const Behavior& b) { return b.name == options.behavior; });
  try {
    referenceBehavior.learner->checkGrid(*referenceBehavior.discretizer);
  } catch (const Error& e) {
    throw Error(fmt::format("{}: behaviors.{}: {}", referenceSets.empty() ? "reference" : "--reference-set",
                            options.behavior, e.what()));
  }
  const std::size_t behaviorVertices =
      checkRunGrids(options, runs, *referenceBehavior.discretizer, !referenceSets.empty(), model, graph.key);

  // The shared behaviours, trained once with the scenario's settings.
  for (const std::string& name : names) {
    if (name == options.behavior) continue;
    TrainSettings train;
    train.behavior = name;
    train.out = base;
    train.resume = true;  // kept when already trained with the same settings
    log(fmt::format("compare: {} (shared by every run)", name));
    trainWithSets(options, options.sets, train, hooks, graph);
  }

  auto trainRun = [&](const Run& run, const std::string& label, bool snapshots) {
    trainCompareRun(options, run, label, snapshots, base, names.size() > 1, snapshotTrials, hooks, graph);
  };
  // The reference takes snapshots when it is one of the runs too (the same bundle).
  const bool referenceIsRun =
      std::any_of(runs.begin(), runs.end(), [&](const Run& r) { return r.dir == reference.dir; });
  trainRun(reference, "reference: value_iteration", referenceIsRun && options.snapshots > 0);
  const PolicyBundle referenceBundle = loadPolicyBundle(reference.dir, model, graph.key);
  const PolicyBehavior& referenceTrained = referenceBundle.behaviors.at(options.behavior);
  const Discretizer& referenceGrid = *referenceBehavior.discretizer;
  const json referenceJson = referenceReport(options, reference, referenceTrained, referenceGrid, behaviorVertices);

  json report = {{"scenario", opened->scenario.path.string()},
                 {"scenario_name", opened->scenario.name},
                 {"behavior", options.behavior},
                 {"learner_names", options.learners},
                 {"seeds", options.seeds},
                 {"trials", options.trials},
                 {"seconds_per_trial", options.seconds},
                 {"reference", referenceJson},
                 {"snapshots", options.snapshots},
                 {"snapshot_trials", options.snapshots > 0 ? json(snapshotTrials) : json(nullptr)},
                 {"runs", json::array()},
                 {"learners", json::object()},
                 {"flags", json::array()}};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Run& run = runs[i];
    const std::string label = run.seeded ? fmt::format("{} seed {}", run.learner, run.seed) : run.learner;
    trainRun(run, fmt::format("[{}/{}] {}", i + 1, runs.size(), label), options.snapshots > 0);
    const json evaluated = evaluateRun(options, run.sets, run.dir, graph);
    const PolicyBundle bundle = loadPolicyBundle(run.dir, model, graph.key);
    const PolicyBehavior& trained = bundle.behaviors.at(options.behavior);
    const Comparison c = compareTables(trained.table, trained.vertices, referenceTrained.table,
                                       referenceTrained.vertices, referenceGrid);
    const json r = runJson(run, trained, evaluated, c, options.snapshots > 0);
    if (!r["snapshots"].is_null()) {
      std::string rates;
      for (const json& p : r["snapshots"]["points"]) rates += fmt::format(" {:.0f}", 100 * p[3].get<double>());
      log(fmt::format("compare: {}: success % along training ({} snapshots of {} trials):{}", label,
                      r["snapshots"]["points"].size(), snapshotTrials, rates));
    }
    if (c.agreement < kAgreementFlag)
      report["flags"].push_back(fmt::format(
          "{}: its greedy policy agrees with the reference's on {:.1f} % of (state, vertex) pairs (value RMSE {:.3g}; "
          "{:.1f} % of its Q entries are not zero)",
          label, 100 * c.agreement, c.rmse, 100 * r["nonzero_share"].get<double>()));
    report["runs"].push_back(r);
  }
  report["learners"] = learnerSummaries(report["runs"], options.learners);
  return report;
}

}  // namespace mgrl
