#include "learn_commands.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "graph_command.hpp"
#include "mgrl/checkpoint_store.hpp"
#include "mgrl/controller.hpp"
#include "mgrl/data_paths.hpp"
#include "mgrl/hash.hpp"
#include "mgrl/motion_io.hpp"
#include "mgrl/parallel.hpp"
#include "mgrl/policy_bundle.hpp"
#include "mgrl/random.hpp"
#include "mgrl/version.hpp"
#include "plugins.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

namespace {

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string humanCount(double n) {
  if (n >= 1e9) return fmt::format("{:.2f} G", n / 1e9);
  if (n >= 1e6) return fmt::format("{:.2f} M", n / 1e6);
  if (n >= 1e3) return fmt::format("{:.1f} k", n / 1e3);
  return fmt::format("{:.0f} ", n);
}

// Progress of one behaviour's training: a bar redrawn in place on a terminal, else a line
// every 10 s through the log.
class ProgressReporter final : public TrainObserver {
 public:
  ProgressReporter(std::string name, bool bar, WarningSink log)
      : name_(std::move(name)), bar_(bar), log_(std::move(log)), start_(Clock::now()) {}
  ~ProgressReporter() override {
    if (drawn_) std::cerr << '\n';
  }

  void progress(const TrainProgress& p) override {
    const double now = since(start_);
    const bool done = p.total > 0 && p.updates >= p.total;
    if (!done && now - last_ < (bar_ ? 0.2 : 10.0)) return;
    last_ = now;
    const double rate = p.seconds > 0 ? static_cast<double>(p.updates) / p.seconds : 0;
    const std::string residual = p.residual < 0 ? std::string("-") : fmt::format("{:.3g}", p.residual);
    std::string line;
    if (p.total > 0) {
      const double fraction = static_cast<double>(p.updates) / static_cast<double>(p.total);
      const double eta = rate > 0 ? static_cast<double>(p.total - p.updates) / rate : 0;
      constexpr int kWidth = 24;
      const int filled = static_cast<int>(fraction * kWidth);
      line = fmt::format("{} [{}{}] {:3.0f}%  {}updates/s  residual {}  ETA {:.0f} s", name_, std::string(filled, '#'),
                         std::string(kWidth - filled, '.'), 100 * fraction, humanCount(rate), residual, eta);
    } else {
      line = fmt::format("{}: {}updates  {}updates/s  largest change {}", name_, humanCount(p.updates),
                         humanCount(rate), residual);
    }
    if (bar_) {
      std::cerr << '\r' << line << "\x1b[K" << std::flush;
      drawn_ = true;
    } else if (log_) {
      log_(line);
    }
  }

 private:
  std::string name_;
  bool bar_;
  WarningSink log_;
  Clock::time_point start_;
  double last_ = -1e9;
  bool drawn_ = false;
};

// Checkpoints in a directory; MGRL_EXIT_AFTER_CHECKPOINTS=N makes the process exit at once
// after the N-th, as a kill would, so crash recovery can be tested without timing races.
class CrashTestCheckpointer final : public Checkpointer {
 public:
  explicit CrashTestCheckpointer(DirectoryCheckpointer& inner) : inner_(inner) {
    if (const char* n = std::getenv("MGRL_EXIT_AFTER_CHECKPOINTS")) exitAfter_ = std::atoi(n);
  }
  void save(const json& state, const QTable& table) override {
    inner_.save(state, table);
    if (exitAfter_ > 0 && ++saved_ >= exitAfter_) {
      std::cerr << "mgrl: MGRL_EXIT_AFTER_CHECKPOINTS: exiting after checkpoint " << saved_ << '\n';
      std::_Exit(75);
    }
  }
  std::optional<json> load(QTable& table) override { return inner_.load(table); }

 private:
  DirectoryCheckpointer& inner_;
  int exitAfter_ = 0, saved_ = 0;
};

struct Loaded {
  Scenario scenario;
  GraphResult graph;
  fs::path cacheDir;
};

// The scenario with its behaviours checked: every mistake that needs no graph is found
// before the graph is built or loaded.
Scenario checkedScenario(const LearnOptions& options) {
  Scenario scenario = loadScenario(options.scenario, dataDirectory(options.dataDir), options.sets);
  if (scenario.behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour (see scenarios/README.md), "
                       "found none");
  checkBehaviors(scenario, plugins());
  return scenario;
}

Loaded load(const LearnOptions& options, Scenario scenario) {
  GraphOptions graphOptions;
  graphOptions.cacheDir = options.cacheDir;
  graphOptions.log = options.log;
  GraphResult graph = obtainGraph(scenario, graphOptions);
  fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  return {std::move(scenario), std::move(graph), std::move(cacheDir)};
}

std::vector<double> vertexPositions(const Discretizer& grid) {
  std::vector<double> out;
  out.reserve(3 * grid.vertexCount());
  for (std::size_t v = 0; v < grid.vertexCount(); ++v) {
    const Eigen::Vector3d p = grid.vertexPosition(v);
    out.insert(out.end(), {p.x(), p.y(), p.z()});
  }
  return out;
}

std::string setFlags(const std::vector<std::string>& sets) {
  std::string text;
  for (const std::string& s : sets) text += fmt::format(" --set {}", s);
  return text;
}

fs::path checkpointDirectory(const fs::path& out, const std::string& behavior) {
  return out.parent_path() / (out.filename().string() + ".checkpoints") / behavior;
}

}  // namespace

fs::path defaultPolicyDirectory(const fs::path& cacheDir, const std::string& scenarioName, const fs::path& scenarioPath) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(scenarioPath, ec);
  return cacheDir / "policies" / fmt::format("{}-{}", scenarioName, hexDigest(hashBytes(canonical.string())).substr(0, 8));
}

json runTrain(const TrainOptions& options) {
  const auto log = [&](const std::string& m) {
    if (options.log) options.log(m);
  };
  Scenario scenario = checkedScenario(options);
  if (!options.behavior.empty()) {
    std::vector<std::string> names;
    for (const BehaviorSpec& spec : scenario.behaviors) names.push_back(spec.name);
    if (std::find(names.begin(), names.end(), options.behavior) == names.end())
      throw Error(fmt::format("--behavior: expected one of the scenario's behaviours ({}), found {}",
                              fmt::join(names, ", "), quoteToken(options.behavior)));
  }
  const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  fs::path out = options.out.empty() ? defaultPolicyDirectory(cacheDir, scenario.name, scenario.path) : options.out;
  if (!out.has_filename()) out = out.parent_path();
  {
    // Fail before hours of training, not after: the bundle's folder must be creatable.
    std::error_code ec;
    if (out.has_parent_path()) fs::create_directories(out.parent_path(), ec);
    if (ec) throw Error(fmt::format("--out {}: cannot create {}: {}", out.string(), out.parent_path().string(), ec.message()));
    if (fs::exists(out, ec) && !fs::is_directory(out, ec))
      throw Error(fmt::format("--out {}: expected a policy bundle directory or nothing, found a file", out.string()));
  }
  Loaded loaded = load(options, std::move(scenario));
  const StateActionModel& model = loaded.graph.model;
  std::vector<Behavior> all = buildBehaviors(loaded.scenario, plugins(), model, loaded.graph.key);

  PolicyBundle bundle;
  bundle.graphKey = loaded.graph.key;
  bundle.provenance = {{"scenario", loaded.scenario.path.string()},
                       {"scenario_name", loaded.scenario.name},
                       {"tool", fmt::format("mgrl {}", kVersion)},
                       {"sets", options.sets}};
  if (!options.behavior.empty() && fs::exists(out / "manifest.json")) {
    // Training one behaviour keeps the others' tables if they are still current.
    try {
      PolicyBundle previous = loadPolicyBundle(out, model, loaded.graph.key);
      for (auto& [name, entry] : previous.behaviors) {
        const auto match = std::find_if(all.begin(), all.end(), [&](const Behavior& b) { return b.name == name; });
        if (name == options.behavior) continue;
        if (match != all.end() && match->key == entry.key)
          bundle.behaviors.emplace(name, std::move(entry));
        else
          log(fmt::format("warning: dropping {}'s table from {}: the scenario {}", name, out.string(),
                          match == all.end() ? "no longer has this behaviour" : "now asks for other settings"));
      }
    } catch (const Error& e) {
      log(fmt::format("warning: not keeping the other behaviours of {}: {}", out.string(), e.what()));
    }
  }

  const unsigned threads = defaultThreadCount();
  json report = {{"scenario", loaded.scenario.path.string()},
                 {"policy", out.string()},
                 {"graph_key", loaded.graph.key},
                 {"behaviors", json::object()}};
  std::vector<fs::path> checkpoints;
  for (Behavior& behavior : all) {
    if (!options.behavior.empty() && behavior.name != options.behavior) continue;
    const Problem problem = behavior.problem(model);
    const auto tabulateStart = Clock::now();
    const GridModel grid = GridModel::build(problem, threads);
    const double tabulateSeconds = since(tabulateStart);
    log(fmt::format("train {}: {} on a {} grid ({} vertices) x {} actions, problem tabulated in {:.2f} s ({} MB)",
                    behavior.name, behavior.learner->type(), behavior.discretizer->type(),
                    behavior.discretizer->vertexCount(), model.actionCount(), tabulateSeconds,
                    grid.bytes() / 1000000));

    DirectoryCheckpointer directory(checkpointDirectory(out, behavior.name), behavior.key, model,
                                    behavior.discretizer->vertexCount(), options.log);
    if (!options.resume) directory.remove();
    CrashTestCheckpointer checkpointer(directory);
    checkpoints.push_back(directory.directory());
    ProgressReporter progress(behavior.name, options.progressBar, options.log);
    TrainResult result = behavior.learner->train({problem, grid, &progress, &checkpointer, threads});

    json curve = json::array();
    for (const CurvePoint& p : result.curve) curve.push_back({p.updates, p.seconds, p.residual, p.meanResidual});
    const double rate = result.seconds > 0 ? static_cast<double>(result.updates) / result.seconds : 0;
    json summary = {{"learner", behavior.learner->type()},
                    {"updates", result.updates},
                    {"seconds", result.seconds},
                    {"updates_per_second", rate},
                    {"final_residual", result.finalResidual},
                    {"table_bytes", result.table.bytes()},
                    {"vertices", behavior.discretizer->vertexCount()},
                    {"actions", model.actionCount()},
                    {"tabulate_seconds", tabulateSeconds},
                    {"stats", result.stats}};
    report["behaviors"][behavior.name] = summary;
    json record = summary;
    record["config"] = behavior.config;
    record["weight"] = behavior.weight;
    record["activation"] = std::string(activationName(behavior.activation));
    record["grid"] = behavior.discretizer->describe();
    record["curve_columns"] = {"updates", "seconds", "residual", "mean_residual"};
    record["curve"] = curve;
    bundle.behaviors[behavior.name] =
        PolicyBehavior{behavior.key, record, std::move(result.table), vertexPositions(*behavior.discretizer)};
    log(fmt::format("train {}: {} updates in {:.2f} s ({}updates/s), Bellman residual {:.3g}", behavior.name,
                    result.updates, result.seconds, humanCount(rate), result.finalResidual));
  }
  savePolicyBundle(out, bundle);
  for (const fs::path& dir : checkpoints) {
    std::error_code ec;
    fs::remove_all(dir, ec);
    fs::remove(dir.parent_path(), ec);  // only if empty
  }
  log(fmt::format("policy: {}", out.string()));
  return report;
}

std::string trainText(const json& report) {
  std::string text = fmt::format("policy bundle: {}\n", report["policy"].get<std::string>());
  for (const auto& [name, b] : report["behaviors"].items())
    text += fmt::format("  {:<10} {:<16} {:>12} updates  {:8.2f} s  {:>9}updates/s  residual {:.3g}  table {:.1f} MB\n",
                        name, b["learner"].get<std::string>(), b["updates"].get<std::uint64_t>(),
                        b["seconds"].get<double>(), humanCount(b["updates_per_second"].get<double>()),
                        b["final_residual"].get<double>(), b["table_bytes"].get<double>() / 1e6);
  return text;
}

namespace {

struct TrialStats {
  std::size_t successes = 0, decisions = 0;
  std::vector<double> hitTimes;
  double returns = 0;
};

// The refusals eval can make from the manifest alone, made before the graph is loaded so
// that they are the only line on stderr. loadPolicyBundle() checks everything afterwards.
void precheckPolicy(const fs::path& dir, const Scenario& scenario, const EvalOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw Error(fmt::format("{}: no policy bundle here: run `mgrl train {}{}` first (or pass --policy DIR)",
                            dir.string(), options.scenario.string(), setFlags(options.sets)));
  json manifest;
  try {
    manifest = json::parse(readFile(dir / "manifest.json"));
  } catch (const std::exception&) {
    return;  // the full load says what is wrong
  }
  if (!manifest.is_object() || !manifest.contains("graph_key") || !manifest["graph_key"].is_string() ||
      !manifest.contains("behaviors") || !manifest["behaviors"].is_object())
    return;
  const std::string graphKey = graphCacheKey(scenario);
  const std::string found = manifest["graph_key"].get<std::string>();
  if (found != graphKey)
    throw Error(fmt::format("{}: expected graph key '{}', found '{}': the policy was made for another graph; "
                            "retrain with mgrl train {}{}",
                            (dir / "manifest.json").string(), graphKey.substr(0, 16), found.substr(0, 16),
                            options.scenario.string(), setFlags(options.sets)));
  for (const BehaviorSpec& spec : scenario.behaviors) {
    const json& entry = manifest["behaviors"].contains(spec.name) ? manifest["behaviors"][spec.name] : json();
    if (entry.is_null())
      throw Error(fmt::format("{}: expected a trained table for behaviour '{}' that the scenario asks for, found "
                              "none; run mgrl train {} --behavior {}{}",
                              dir.string(), spec.name, options.scenario.string(), spec.name, setFlags(options.sets)));
    const std::string key = behaviorConfigAndKey(spec, plugins(), graphKey).second;
    if (entry.is_object() && entry.contains("key") && entry["key"].is_string() && entry["key"] != key)
      throw Error(fmt::format("{}: behaviour '{}' was trained with other settings than the scenario's now (key {} "
                              "vs {}); retrain with mgrl train {} --behavior {}{}",
                              dir.string(), spec.name, entry["key"].get<std::string>().substr(0, 16),
                              key.substr(0, 16), options.scenario.string(), spec.name, setFlags(options.sets)));
  }
}

}  // namespace

json runEval(const EvalOptions& options) {
  if (options.controller != "policy" && options.controller != "random")
    throw Error(fmt::format("--controller: expected one of: policy, random, found {}", quoteToken(options.controller)));
  if (options.trials < 1 || options.trials > 10'000'000)
    throw Error(fmt::format("--trials: expected a number of trials in [1, 10000000], found {}", options.trials));
  if (!(options.seconds > 0 && options.seconds <= 3600))
    throw Error(fmt::format("--seconds: expected seconds of motion per trial in (0, 3600], found {}", options.seconds));
  Scenario scenario = checkedScenario(options);
  const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  const fs::path dir =
      options.policy.empty() ? defaultPolicyDirectory(cacheDir, scenario.name, scenario.path) : options.policy;
  if (options.controller == "policy") precheckPolicy(dir, scenario, options);
  Loaded loaded = load(options, std::move(scenario));
  const StateActionModel& model = loaded.graph.model;
  std::vector<Behavior> behaviors = buildBehaviors(loaded.scenario, plugins(), model, loaded.graph.key);

  PolicyBundle bundle;
  std::vector<PolicyPart> parts;
  if (options.controller == "policy") {
    bundle = loadPolicyBundle(dir, model, loaded.graph.key);
    for (const Behavior& b : behaviors) {
      const auto found = bundle.behaviors.find(b.name);
      if (found == bundle.behaviors.end())
        throw Error(fmt::format("{}: expected a trained table for behaviour '{}' that the scenario asks for, found "
                                "none; run mgrl train {} --behavior {}{}",
                                dir.string(), b.name, options.scenario.string(), b.name, setFlags(options.sets)));
      if (found->second.key != b.key)
        throw Error(fmt::format("{}: behaviour '{}' was trained with other settings than the scenario's now (key {} "
                                "vs {}); retrain with mgrl train {} --behavior {}{}",
                                dir.string(), b.name, found->second.key.substr(0, 16), b.key.substr(0, 16),
                                options.scenario.string(), b.name, setFlags(options.sets)));
      parts.push_back({b.discretizer.get(), &found->second.table, b.weight, b.activation});
    }
  }

  // The approach region: the first always-active behaviour's grid, sampled uniformly by area.
  const auto region = std::find_if(behaviors.begin(), behaviors.end(),
                                   [](const Behavior& b) { return b.activation == Activation::Always; });
  const Discretizer& regionGrid = *(region != behaviors.end() ? region : behaviors.begin())->discretizer;
  double reach = 0;
  for (const GridAxis& axis : regionGrid.axes())
    if (axis.name == "distance") reach = axis.vertices.back();
  if (!(reach > 0))
    throw Error(fmt::format("{}: expected a behaviour whose grid has a distance axis to place targets in, found none",
                            loaded.scenario.path.string()));
  // The target's height: given, else that of the effective hitting points' centroid (a
  // target at punching height, as the user's target in the paper's demo).
  const double targetHeight = std::isnan(options.targetHeight) ? model.centroid[1] : options.targetHeight;
  double contactRadius = 0.15;
  // A hit lands within the first hit reward's contact radius; returns are discounted with
  // the first behaviour's gamma.
  for (const Behavior& b : behaviors)
    if (b.reward->type() == "hit") {
      contactRadius = b.config["reward"].value("contact_radius", contactRadius);
      break;
    }
  const double gamma = behaviors.front().reward->gamma();
  const StaticTarget environment;
  PolicyController controller(model, parts);

  auto run = [&](const std::string& kind, std::vector<std::pair<std::uint32_t, Eigen::Vector3d>>* decisions) {
    Rng starts(options.seed), choices(options.seed ^ 0x5eed5eed5eedULL);
    TrialStats stats;
    const double limit = options.seconds / model.frameTime;
    for (std::size_t trial = 0; trial < options.trials; ++trial) {
      auto s = static_cast<std::uint32_t>(starts.below(model.stateCount()));
      Eigen::Vector3d e;
      do e = {(2 * starts.uniform() - 1) * reach, 0, (2 * starts.uniform() - 1) * reach};
      while (!regionGrid.inside(e));
      e.y() = targetHeight;
      double elapsed = 0, discount = 1, trialReturn = 0;
      bool hit = false;
      while (elapsed < limit && !hit) {
        std::size_t a;
        if (kind == "policy") {
          if (decisions) decisions->emplace_back(s, e);
          a = controller.choose(s, e);
        } else {
          a = model.stateActionBegin[s] + choices.below(model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
        }
        ++stats.decisions;
        double reward = 0;
        for (const Behavior& b : behaviors) {
          if (b.activation == Activation::TargetInside && !b.discretizer->inside(e)) continue;
          reward += b.weight * b.reward->evaluate(model, a, e);
        }
        trialReturn += discount * reward;
        for (const ActionHit& h : model.hitsOf(a)) {
          const Eigen::Vector3d fist(h.x, h.y, h.z);
          if ((fist - e).norm() <= contactRadius) {
            hit = true;
            stats.hitTimes.push_back((elapsed + h.offset) * model.frameTime);
            break;
          }
        }
        const auto frames = static_cast<double>(model.actionLength(a));
        discount *= std::pow(gamma, frames);
        elapsed += frames;
        e = environment.next(model, a, e);
        s = model.actionTo[a];
      }
      stats.successes += hit;
      stats.returns += trialReturn;
    }
    return stats;
  };

  auto summarize = [&](TrialStats& stats) {
    std::sort(stats.hitTimes.begin(), stats.hitTimes.end());
    const std::size_t n = stats.hitTimes.size();
    double mean = 0;
    for (double t : stats.hitTimes) mean += t;
    json times = nullptr, median = nullptr;
    if (n > 0) {
      times = mean / static_cast<double>(n);
      median = n % 2 ? stats.hitTimes[n / 2] : (stats.hitTimes[n / 2 - 1] + stats.hitTimes[n / 2]) / 2;
    }
    return json{{"success_rate", static_cast<double>(stats.successes) / static_cast<double>(options.trials)},
                {"successes", stats.successes},
                {"mean_time_to_hit_s", times},
                {"median_time_to_hit_s", median},
                {"mean_return", stats.returns / static_cast<double>(options.trials)},
                {"decisions", stats.decisions}};
  };

  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> decisions;
  TrialStats stats = run(options.controller, options.controller == "policy" ? &decisions : nullptr);
  json report = summarize(stats);
  // Decision cost, measured apart from the simulation: replay the trials' decisions.
  double perSecond = 0;
  if (options.controller == "policy" && !decisions.empty()) {
    std::size_t sink = 0, calls = 0;
    const auto start = Clock::now();
    do {
      for (const auto& [s, e] : decisions) sink += controller.choose(s, e);
      calls += decisions.size();
    } while (since(start) < 0.2);
    perSecond = static_cast<double>(calls) / since(start);
    if (sink == 1) std::cerr << "";  // keep the calls
  } else {
    const auto start = Clock::now();
    Rng rng(options.seed);
    std::size_t sink = 0, calls = 0;
    do {
      for (int i = 0; i < 100000; ++i) {
        const auto s = static_cast<std::uint32_t>(rng.below(model.stateCount()));
        sink += model.stateActionBegin[s] + rng.below(model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
      }
      calls += 100000;
    } while (since(start) < 0.2);
    perSecond = static_cast<double>(calls) / since(start);
    if (sink == 1) std::cerr << "";
  }
  report["decisions_per_second"] = perSecond;
  report["controller"] = options.controller;
  report["trials"] = options.trials;
  report["seed"] = options.seed;
  report["seconds_per_trial"] = options.seconds;
  report["contact_radius_m"] = contactRadius;
  report["target_height_m"] = targetHeight;
  if (options.controller == "policy") {
    report["policy"] = dir.string();
    TrialStats baseline = run("random", nullptr);
    report["random_baseline"] = summarize(baseline);
  }
  return report;
}

std::string evalText(const json& r) {
  auto optional = [](const json& v) { return v.is_null() ? std::string("-") : fmt::format("{:.2f} s", v.get<double>()); };
  std::string text = fmt::format(
      "controller {}: {} trials, success rate {:.1f} %, time to hit mean {} median {}, mean return {:.3f}, {} "
      "decisions/s\n",
      r["controller"].get<std::string>(), r["trials"].get<std::size_t>(), 100 * r["success_rate"].get<double>(),
      optional(r["mean_time_to_hit_s"]), optional(r["median_time_to_hit_s"]), r["mean_return"].get<double>(),
      humanCount(r["decisions_per_second"].get<double>()));
  if (r.contains("random_baseline")) {
    const json& b = r["random_baseline"];
    text += fmt::format("random baseline on the same starts: success rate {:.1f} %, time to hit mean {}, mean return "
                        "{:.3f}\n",
                        100 * b["success_rate"].get<double>(), optional(b["mean_time_to_hit_s"]),
                        b["mean_return"].get<double>());
  }
  return text;
}

}  // namespace mgrl::app
