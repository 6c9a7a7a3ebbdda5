// `mgrl train` (DESIGN.md sec. 5): trains a scenario's behaviours and saves a policy bundle.
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <set>

#include "learn_common.hpp"
#include "mgrl/session/session.hpp"

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/launch.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/checkpoint_store.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "plugins.hpp"
#include "self_play.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Progress of one behaviour's training: a bar redrawn in place on a terminal, else a line
// every 10 s through the log.
class ProgressReporter final : public TrainObserver {
 public:
  ProgressReporter(std::string name, bool bar, WarningSink log, TrainListener* listener)
      : name_(std::move(name)), bar_(bar), log_(std::move(log)), listener_(listener), start_(Clock::now()) {}
  ~ProgressReporter() override {
    if (drawn_) std::cerr << '\n';
  }

  std::size_t snapshotCount() const override { return listener_ ? listener_->snapshotCount() : 0; }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override {
    if (listener_) listener_->snapshot(table, point, grid);
  }

  void note(const std::string& text) override {
    if (drawn_) {
      std::cerr << '\n';
      drawn_ = false;
    }
    if (log_) log_(fmt::format("{}: {}", name_, text));
  }

  void progress(const TrainProgress& p) override {
    if (listener_) listener_->progress(p);
    const double now = since(start_);
    const bool done = p.total > 0 && p.updates >= p.total;
    if (!done && now - last_ < (bar_ ? 0.2 : 10.0)) return;
    last_ = now;
    const double rate = p.seconds > 0 ? static_cast<double>(p.updates) / p.seconds : 0;
    // Before the first measurement there is no residual to show: say nothing of it.
    const std::string residual = p.residual < 0 ? std::string() : fmt::format("  residual {:.3g}", p.residual);
    std::string line;
    if (p.total > 0) {
      const double fraction = static_cast<double>(p.updates) / static_cast<double>(p.total);
      const double eta = rate > 0 ? static_cast<double>(p.total - p.updates) / rate : 0;
      constexpr int kWidth = 24;
      const int filled = static_cast<int>(fraction * kWidth);
      line = fmt::format("{} [{}{}] {:3.0f}%  {}updates/s{}  ETA {:.0f} s", name_, std::string(filled, '#'),
                         std::string(kWidth - filled, '.'), 100 * fraction, humanCount(rate), residual, eta);
    } else {
      line = fmt::format("{}: {}updates  {}updates/s{}", name_, humanCount(p.updates), humanCount(rate),
                         p.residual < 0 ? std::string() : fmt::format("  largest change {:.3g}", p.residual));
    }
    if (listener_) {
      const std::string status = listener_->status();
      if (!status.empty()) line += "  " + status;
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
  TrainListener* listener_;
  Clock::time_point start_;
  double last_ = -1e9;
  bool drawn_ = false;
};

// Ctrl-C and SIGTERM while training raise this flag: the learner stops at its next safe
// point and saves a checkpoint; what had finished is kept. A second Ctrl-C kills at once.
std::atomic<bool> stopRequested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onStopSignal(int) { stopRequested.store(true); }

class StopSignals {
 public:
  StopSignals() {
    stopRequested.store(false);
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &oldInt_);
    sigaction(SIGTERM, &action, &oldTerm_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &oldInt_, nullptr);
    sigaction(SIGTERM, &oldTerm_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction oldInt_ {}, oldTerm_ {};
};

// Checkpoints in a directory; MGRL_EXIT_AFTER_CHECKPOINTS=N makes the process exit at once
// after the N-th, as a kill would, so crash recovery can be tested without timing races.
// MGRL_STOP_AFTER_CHECKPOINTS=N raises the stop flag after the N-th, as a Ctrl-C would.
// A resumed run says where it resumed from.
class CrashTestCheckpointer final : public Checkpointer {
 public:
  CrashTestCheckpointer(DirectoryCheckpointer& inner, std::string behavior, WarningSink log)
      : inner_(inner), behavior_(std::move(behavior)), log_(std::move(log)) {
    if (const char* n = std::getenv("MGRL_EXIT_AFTER_CHECKPOINTS")) exitAfter_ = std::atoi(n);
    if (const char* n = std::getenv("MGRL_STOP_AFTER_CHECKPOINTS")) stopAfter_ = std::atoi(n);
  }
  void save(const json& state, const QTable& table) override {
    inner_.save(state, table);
    ++saved_;
    if (exitAfter_ > 0 && saved_ >= exitAfter_) {
      std::cerr << "mgrl: MGRL_EXIT_AFTER_CHECKPOINTS: exiting after checkpoint " << saved_ << '\n';
      std::_Exit(75);
    }
    if (stopAfter_ > 0 && saved_ == stopAfter_) stopRequested.store(true);
  }
  std::optional<json> load(QTable& table) override { return said(inner_.load(table)); }
  // The learner's own check of its state runs inside the directory checkpointer, which
  // reports a rejected state (naming state.json) and ignores the checkpoint.
  std::optional<json> loadChecked(QTable& table, const StateCheck& check) override {
    return said(inner_.loadChecked(table, check));
  }
  bool resumed() const { return resumed_; }

 private:
  std::optional<json> said(std::optional<json> state) {
    if (state && log_) {
      const json updates = state->is_object() && state->contains("updates") ? (*state)["updates"] : json();
      log_(fmt::format("resume: {}: continuing from the checkpoint{} in {}", behavior_,
                       updates.is_number_unsigned() ? fmt::format(" at {} actions", updates.get<std::uint64_t>()) : "",
                       inner_.directory().string()));
    }
    resumed_ = state.has_value();
    return state;
  }

  DirectoryCheckpointer& inner_;
  std::string behavior_;
  WarningSink log_;
  int exitAfter_ = 0, stopAfter_ = 0, saved_ = 0;
  bool resumed_ = false;
};

fs::path checkpointDirectory(const fs::path& out, const std::string& behavior) {
  return out.parent_path() / (out.filename().string() + ".checkpoints") / behavior;
}

// After a finished run: a behaviour's checkpoint, what killed writers left beside it
// (issue 19), and the checkpoints folder once nothing else is in it.
void removeCheckpoint(const fs::path& dir) {
  std::error_code ec;
  for (const StaleSibling& stale : staleSiblings(dir)) fs::remove_all(stale.path, ec);
  fs::remove_all(dir, ec);
  fs::remove(dir.parent_path(), ec);  // only if empty
}

}  // namespace


namespace {

// A stopped run keeps what had finished: the bundle is saved with the finished tables and
// the unfinished behaviours named in its provenance (so eval and simulate refuse it,
// saying to resume, instead of taking it for a whole one), then the run ends with
// Interrupted saying how to continue.
[[noreturn]] void interrupted(const TrainOptions& options, const fs::path& out, PolicyBundle& bundle,
                              const std::vector<std::string>& wanted, const std::string& current,
                              const TrainInterrupted& stop, const fs::path& checkpoint) {
  // A table of the current behaviour from an earlier run is still right (same key).
  std::vector<std::string> unfinished;
  for (const std::string& name : wanted)
    if (bundle.behaviors.count(name) == 0) unfinished.push_back(name);
  std::vector<std::string> kept;
  for (const auto& entry : bundle.behaviors) kept.push_back(entry.first);
  std::string keptText = "nothing had finished";
  if (!kept.empty()) {
    bundle.provenance["unfinished"] = unfinished;
    savePolicyBundle(out, bundle);
    keptText = fmt::format("kept {} in {}", fmt::join(kept, ", "), out.string());
  }
  const std::string where =
      stop.checkpointed()
          ? fmt::format("checkpoint at {} of {} actions in {}", stop.updates(), stop.total(), checkpoint.string())
          : std::string("no checkpoint: it starts over");
  std::string command = fmt::format("mgrl train {}", options.scenario.string());
  if (!options.behavior.empty()) command += fmt::format(" --behavior {}", options.behavior);
  command += setFlags(options.sets);
  if (!options.out.empty()) command += fmt::format(" --out {}", options.out.string());
  throw Interrupted(fmt::format("interrupted while training {} ({}); {}; run `{} --resume` to continue", current,
                                where, keptText, command));
}

}  // namespace

json runTrain(const TrainOptions& given) {
  // Under an MPI launcher (issue 44: `mpirun -np K mgrl train`), every process runs the
  // command, a distributed learner's ranks train together, and rank 0 alone writes (the
  // bundle, checkpoints) and speaks; the others read the same files and stay silent.
  const bool writes = launchedProcess().rank == 0;
  TrainOptions options = given;
  if (!writes) {
    options.log = nullptr;
    options.progressBar = false;
    options.listen = nullptr;
  }
  const auto log = [&](const std::string& m) {
    if (options.log) options.log(m);
  };
  // The scenario, its graph and behaviours, and the task they share (behaviours that do not
  // share one world are refused here, not after training); the model is enough: no poses.
  fs::path out;
  SessionNeeds needs;
  needs.motion = false;
  needs.beforeGraph = [&](const Scenario& scenario) {
    if (!options.behavior.empty()) requireBehavior(scenario, options.behavior);
    const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
    out = options.out.empty() ? defaultPolicyDirectory(cacheDir, scenario) : options.out;
    if (!out.has_filename()) out = out.parent_path();
    {
      // Fail before hours of training, not after: the bundle's folder must be creatable.
      std::error_code ec;
      if (out.has_parent_path()) fs::create_directories(out.parent_path(), ec);
      if (ec) throw Error(fmt::format("--out {}: cannot create {}: {}", out.string(), out.parent_path().string(), ec.message()));
      if (fs::exists(out, ec) && !fs::is_directory(out, ec))
        throw Error(fmt::format("--out {}: expected a policy bundle directory or nothing, found a file", out.string()));
      // The bundle is written beside `out` and renamed into place: that folder must take a
      // new file now, not after training (issue 19). The probe is `.<name>.probe-PID`.
      const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
      if (!folderTakesNewFiles(parent, fmt::format(".{}.probe-", out.filename().string())))
        throw Error(fmt::format("--out {}: expected a folder where files can be written, found {} is not writable",
                                out.string(), parent.string()));
    }
  };
  const std::unique_ptr<Session> session = openSession(options, needs);
  const Scenario& scenario = session->scenario;
  const GraphResult& graph = session->graph;
  const StateActionModel& model = session->model();
  std::vector<Behavior>& all = session->behaviors;

  PolicyBundle bundle;
  bundle.graphKey = graph.key;
  bundle.provenance = {{"scenario", scenario.path.string()},
                       {"scenario_name", scenario.name},
                       {"tool", fmt::format("mgrl {}", kVersion)},
                       {"sets", options.sets}};
  // Tables already in the bundle that are still current (same key: the same settings on
  // the same graph, so the same table) are kept: those of other behaviours when training
  // one, those a stopped run finished when resuming, and all of them until replaced.
  std::set<std::string> finished;
  if (fs::exists(out / "manifest.json")) {
    try {
      PolicyBundle previous = loadPolicyBundle(out, model, graph.key);
      // A stopped run's bundle holds only finished tables (its unfinished ones are absent).
      for (auto& item : previous.behaviors) {
        // Named, not a structured binding: clang before 16 cannot capture one in the lambda.
        const std::string& name = item.first;
        auto& entry = item.second;
        // A self-play round's table (NAME-roundK) belongs to behaviour NAME.
        std::string base = name;
        if (const auto cut = name.rfind("-round"); cut != std::string::npos && cut > 0) base = name.substr(0, cut);
        const auto match = std::find_if(all.begin(), all.end(), [&](const Behavior& b) {
          return b.name == name || (b.name == base && b.environment->rounds() > 1);
        });
        if (match != all.end() && match->key == entry.key) {
          bundle.behaviors.emplace(name, std::move(entry));
          if (options.resume && match->name == name) finished.insert(name);
        } else {
          log(fmt::format("warning: dropping {}'s table from {}: the scenario {}", name, out.string(),
                          match == all.end() ? "no longer has this behaviour" : "now asks for other settings"));
        }
      }
    } catch (const Error& e) {
      log(fmt::format("warning: not keeping the behaviours already in {}: {}", out.string(), e.what()));
    }
  }

  const unsigned threads = defaultThreadCount();
  json report = {{"scenario", scenario.path.string()},
                 {"policy", out.string()},
                 {"graph_key", graph.key},
                 {"behaviors", json::object()}};
  std::vector<std::string> wanted;
  for (const Behavior& behavior : all)
    if (options.behavior.empty() || behavior.name == options.behavior) wanted.push_back(behavior.name);
  // Issue 19: every behaviour's size is checked before anything is allocated or trained,
  // not found by bad_alloc, nor after training the others.
  std::map<std::string, bool> compactModel;
  for (const Behavior& behavior : all) {
    if (std::find(wanted.begin(), wanted.end(), behavior.name) == wanted.end()) continue;
    try {
      behavior.learner->checkGrid(*behavior.discretizer);
    } catch (const Error& e) {
      throw Error(fmt::format("behaviors.{}: {}", behavior.name, e.what()));
    }
    // Issue 20: the tabulated model when it fits (or is asked for), else the compact one.
    // A refining learner's tables grow to its vertex budget (adaptive_value_iteration).
    const std::size_t vertices = behavior.learner->trainingVertices(*behavior.discretizer);
    const double extra = static_cast<double>(behavior.learner->extraTables()) * static_cast<double>(vertices) *
                         static_cast<double>(model.actionCount()) * sizeof(float);
    // A distributed learner knows its share (issue 44).
    const double share = behavior.learner->bytesPerProcess(model.actionCount(), vertices);
    const double tabulatedBytes =
        (share >= 0 ? share : GridModel::trainingBytes(model.actionCount(), vertices, false)) + extra;
    const double compactBytes = GridModel::trainingBytes(model.actionCount(), vertices, true) + extra;
    const bool canCompact = behavior.learner->takesCompactModel();
    if (options.model == "compact" && !canCompact)
      throw Error(fmt::format("behaviors.{}: --model compact: expected a learner that takes a compact model "
                              "(q_learning, value_iteration), found {}; use --model tabulated or auto",
                              behavior.name, behavior.learner->type()));
    const bool compact = options.model == "compact" ||
                         (options.model == "auto" && tabulatedBytes > options.maxMemoryBytes && canCompact);
    const double needed = compact ? compactBytes : tabulatedBytes;
    // A learned opponent's states multiply the grid (issue 43): say by how much.
    const std::size_t opponentStates = behavior.environment->opponentStates();
    const std::string opponentNote = opponentStates > 0
                                         ? fmt::format(
                                               " (a learned opponent's {} states times {} positions: fewer phases or a "
                                               "coarser grid shrink it; a table larger than one machine trains with "
                                               "mpi_value_iteration across machines, docs/distributed.md)",
                                               opponentStates, behavior.discretizer->layerVertexCount())
                                         : std::string();
    if (needed > options.maxMemoryBytes)
      throw Error(fmt::format(
          "behaviors.{}: training on a {} grid of {}{} vertices{} x {} actions needs about {} "
          "({} model and Q tables{}); expected at most {} (--max-memory): use a coarser grid{}, or "
          "raise --max-memory",
          behavior.name, behavior.discretizer->type(), vertices > behavior.discretizer->vertexCount() ? "up to " : "",
          vertices, opponentNote, model.actionCount(), humanBytes(needed), compact ? "compact" : "tabulated",
          extra > 0 ? fmt::format(", {} more tables held", behavior.learner->extraTables()) : "",
          humanBytes(options.maxMemoryBytes),
          !compact && canCompact && compactBytes <= options.maxMemoryBytes
              ? fmt::format(", --model compact (about {})", humanBytes(compactBytes))
              : ""));
    compactModel[behavior.name] = compact;
    if (compact && options.model == "auto")
      log(fmt::format("train {}: the tabulated model and tables would need about {}, over --max-memory {}: using "
                      "the compact model (about {}; same tables, slower backups)",
                      behavior.name, humanBytes(tabulatedBytes), humanBytes(options.maxMemoryBytes),
                      humanBytes(compactBytes)));
  }
  std::vector<fs::path> checkpoints;
  const StopSignals signals;
  for (Behavior& behavior : all) {
    if (std::find(wanted.begin(), wanted.end(), behavior.name) == wanted.end()) continue;
    if (finished.count(behavior.name) != 0) {
      log(fmt::format("resume: {}: already trained in {}, kept", behavior.name, out.string()));
      report["kept"].push_back(behavior.name);
      // A run killed after its bundle was in place may have left its checkpoints.
      checkpoints.push_back(checkpointDirectory(out, behavior.name));
      continue;
    }
    // Self-play rounds (issue 43): round 1 against the opponent the scenario names, round k
    // against round k - 1's table; each round's table is kept, the last under the
    // behaviour's own name, the others as NAME-roundK.
    const int rounds = behavior.environment->rounds();
    std::shared_ptr<const QTable> previous;
    json roundsReport = json::array();
    for (int round = 1; round <= rounds; ++round) {
      const std::string label = round < rounds ? fmt::format("{}-round{}", behavior.name, round) : behavior.name;
      const std::string roundKey = rounds > 1 ? fmt::format("{}-round{}", behavior.key, round) : behavior.key;
      if (rounds > 1) {
        if (previous)
          behavior.environment->playPolicy(behavior.discretizer.get(), previous, fmt::format("round {}", round - 1));
        log(fmt::format("train {}: self-play round {} of {}, against {}", behavior.name, round, rounds,
                        previous ? fmt::format("round {}'s table", round - 1)
                                 : fmt::format("the {} opponent", behavior.environment->policyKey())));
      }
      const Problem problem = behavior.problem(model);
      const auto tabulateStart = Clock::now();
      const bool compact = compactModel.at(behavior.name);
      // A learner that tabulates itself (each MPI rank its share) gets the model's frame only.
      const bool itself = !compact && behavior.learner->tabulatesItself();
      if (const int ranks = launchedProcess().size; ranks > 1 && !behavior.learner->tabulatesItself())
        log(
            fmt::format("train {}: {} runs in one process: the other {} ranks of this MPI job repeat it and keep "
                        "nothing (mpi_value_iteration shares the work)",
                        label, behavior.learner->type(), ranks - 1));
      const GridModel grid = compact  ? GridModel::buildCompact(problem, threads)
                             : itself ? GridModel::frame(problem)
                                      : GridModel::build(problem, threads);
      const double tabulateSeconds = since(tabulateStart);
      if (itself)
        log(fmt::format("train {}: {} on a {} grid ({} vertices) x {} actions, tabulated by the learner", label,
                        behavior.learner->type(), behavior.discretizer->type(), behavior.discretizer->vertexCount(),
                        model.actionCount()));
      else
        log(fmt::format("train {}: {} on a {} grid ({} vertices) x {} actions, {} tabulated in {:.2f} s ({} MB)", label,
                        behavior.learner->type(), behavior.discretizer->type(), behavior.discretizer->vertexCount(),
                        model.actionCount(), compact ? "rewards (compact model)" : "problem", tabulateSeconds,
                        grid.bytes() / 1000000));

      DirectoryCheckpointer directory(checkpointDirectory(out, label), roundKey, model,
                                      behavior.discretizer->vertexCount(), options.log);
      if (!options.resume && writes) directory.remove();
      CrashTestCheckpointer checkpointer(directory, behavior.name, options.log);
      checkpoints.push_back(directory.directory());
      std::optional<TrainResult> trained;
      std::unique_ptr<TrainListener> listener = options.listen ? options.listen(behavior, all, graph) : nullptr;
      {
        ProgressReporter progress(label, options.progressBar, options.log, listener.get());
        try {
          trained = behavior.learner->train(
              {problem, grid, &progress, writes ? &checkpointer : nullptr, threads, &stopRequested, round < rounds});
        } catch (const TrainInterrupted& stop) {
          if (!writes) throw;
          interrupted(options, out, bundle, wanted, behavior.name, stop, directory.directory());
        }
      }
      if (options.resume && !checkpointer.resumed())
        log(fmt::format("resume: {}: no checkpoint to continue from, trained from the start", behavior.name));
      TrainResult& result = *trained;

      // An adaptive learner returns the grid it refined: the table's vertices are its.
      const Discretizer& tableGrid = result.grid ? *result.grid : *behavior.discretizer;
      json curve = json::array();
      for (const CurvePoint& p : result.curve) curve.push_back({p.updates, p.seconds, p.residual, p.meanResidual});
      const double rate = result.seconds > 0 ? static_cast<double>(result.updates) / result.seconds : 0;
      json summary = {{"learner", behavior.learner->type()},
                      {"updates", result.updates},
                      {"seconds", result.seconds},
                      {"updates_per_second", rate},
                      {"final_residual", result.finalResidual},
                      {"table_bytes", result.table.bytes()},
                      {"vertices", tableGrid.vertexCount()},
                      {"actions", model.actionCount()},
                      {"tabulate_seconds", tabulateSeconds},
                      {"stats", result.stats}};
      if (round == rounds) {
        report["behaviors"][behavior.name] = summary;
        report["behaviors"][behavior.name]["model"] = compact ? "compact" : "tabulated";
        report["behaviors"][behavior.name]["model_bytes"] = grid.bytes();
      }
      json record = summary;
      record["config"] = behavior.config;
      record["weight"] = behavior.weight;
      record["activation"] = std::string(activationName(behavior.activation));
      record["grid"] = tableGrid.describe();
      record["curve_columns"] = {"updates", "seconds", "residual", "mean_residual"};
      record["curve"] = curve;
      if (listener) {
        json snapshots = listener->record();
        if (!snapshots.is_null()) record["snapshots"] = std::move(snapshots);
      }
      log(fmt::format("train {}: {} updates in {:.2f} s ({}updates/s), Bellman residual {:.3g}", label, result.updates,
                      result.seconds, humanCount(rate), result.finalResidual));
      if (rounds > 1) {
        // Scoring the round is reporting: rank 0's (issue 44).
        if (writes) roundsReport.push_back(selfPlayRound(behavior, model, round, result.table, previous.get(), log));
        record["round"] = round;
        record["rounds"] = roundsReport;
        report["behaviors"][behavior.name]["rounds"] = roundsReport;
        if (round < rounds) previous = std::make_shared<const QTable>(result.table);
      }
      bundle.behaviors[round == rounds ? behavior.name : label] = PolicyBehavior{
          behavior.key,          record, std::move(result.table), vertexPositions(tableGrid), tableGrid.type(),
          tableGrid.structure(), nullptr};
    }
  }
  if (bundle.provenance.contains("unfinished")) bundle.provenance.erase("unfinished");
  if (!writes) return report;
  savePolicyBundle(out, bundle);
  for (const fs::path& dir : checkpoints) removeCheckpoint(dir);
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
  if (report.contains("kept"))
    for (const json& name : report["kept"])
      text += fmt::format("  {:<10} kept: trained before the run was stopped\n", name.get<std::string>());
  return text;
}

}  // namespace mgrl::app
