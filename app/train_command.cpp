// `mgrl train` (DESIGN.md sec. 5): trains a scenario's behaviours and saves a policy bundle.
#include <cstdlib>
#include <iostream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "learn_common.hpp"
#include "mgrl/behavior.hpp"
#include "mgrl/checkpoint_store.hpp"
#include "mgrl/hash.hpp"
#include "mgrl/parallel.hpp"
#include "mgrl/policy_bundle.hpp"
#include "mgrl/version.hpp"
#include "plugins.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

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

std::vector<double> vertexPositions(const Discretizer& grid) {
  std::vector<double> out;
  out.reserve(3 * grid.vertexCount());
  for (std::size_t v = 0; v < grid.vertexCount(); ++v) {
    const Eigen::Vector3d p = grid.vertexPosition(v);
    out.insert(out.end(), {p.x(), p.y(), p.z()});
  }
  return out;
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

}  // namespace mgrl::app
