// Training a scenario's behaviours (training.hpp): the memory plan, self-play rounds and
// checkpoints, for every front end. What goes into the bundle (its folder, provenance and
// records, the tables kept, a stopped run's partial bundle) is in train_bundle.cpp.
#include "mgrl/session/training.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <utility>

#include <fmt/format.h>

#include "mgrl/core/launch.hpp"
#include "mgrl/core/numbers.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/checkpoint_store.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/graph_source.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/self_play.hpp"
#include "mgrl/session/train_bundle.hpp"
#include "mgrl/session/train_progress.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;

fs::path checkpointDirectory(const fs::path& out, const std::string& behavior) {
  return out.parent_path() / (out.filename().string() + ".checkpoints") / behavior;
}

void removeCheckpoint(const fs::path& dir) {
  std::error_code ec;
  for (const StaleSibling& stale : staleSiblings(dir)) fs::remove_all(stale.path, ec);
  fs::remove_all(dir, ec);
  fs::remove(dir.parent_path(), ec);  // only if empty
}

namespace {

using Log = std::function<void(const std::string&)>;

// ", 2 more tables held", ", 6.5 more tables held by 4 self-play rounds", ", 8.5 more tables
// held (6.5 by 4 self-play rounds)", or "" for none.
std::string heldText(std::size_t learnerTables, double selfPlayTables, int rounds) {
  if (selfPlayTables == 0)
    return learnerTables > 0 ? fmt::format(", {} more tables held", learnerTables) : std::string();
  if (learnerTables == 0) return fmt::format(", {:g} more tables held by {} self-play rounds", selfPlayTables, rounds);
  return fmt::format(", {:g} more tables held ({:g} by {} self-play rounds)",
                     static_cast<double>(learnerTables) + selfPlayTables, selfPlayTables, rounds);
}

// A behaviour's size is checked before anything is allocated or trained, not found by
// bad_alloc, nor after training the others. The tabulated model when it fits (or is asked
// for), else the compact one. Returns true for the compact model.
bool choosesCompactModel(const Behavior& behavior, const Learner& learner, const StateActionModel& model,
                         const TrainSettings& options, const Log& log) {
  try {
    learner.checkGrid(*behavior.discretizer);
  } catch (const Error& e) {
    throw Error(fmt::format("behaviors.{}: {}", behavior.name, e.what()));
  }
  // A refining learner's tables grow to its vertex budget (adaptive_value_iteration).
  const std::size_t vertices = learner.trainingVertices(*behavior.discretizer);
  // Self-play holds tables beside the learner's: every finished round's (the
  // bundle keeps them), the opponent's (a copy of the previous round's, and with `against:
  // average` the mean), and while a round's best-response gap is measured, its own table
  // beside policy evaluation's pair and chosen actions (2.5 tables) where the learner's pair
  // stood: 1.5 more.
  const SelfPlayOpponent* selfPlay = behavior.environment->as<SelfPlayOpponent>();
  const int rounds = selfPlay ? selfPlay->rounds() : 1;
  const double selfPlayTables = rounds > 1 ? (rounds - 1) + (selfPlay->roundsAgainstAverage() ? 2 : 1) + 1.5 : 0;
  const double extraTables = static_cast<double>(learner.extraTables()) + selfPlayTables;
  const double extra =
      extraTables * static_cast<double>(vertices) * static_cast<double>(model.actionCount()) * sizeof(float);
  // A distributed learner knows its share.
  const double share = learner.bytesPerProcess(model.actionCount(), vertices);
  const double tabulatedBytes =
      (share >= 0 ? share : GridModel::trainingBytes(model.actionCount(), vertices, false)) + extra;
  const double compactBytes = GridModel::trainingBytes(model.actionCount(), vertices, true) + extra;
  const bool canCompact = learner.takesCompactModel();
  if (options.model == "compact" && !canCompact)
    throw Error(
        fmt::format("behaviors.{}: --model compact: expected a learner that takes a compact model "
                    "(q_learning, value_iteration), found {}; use --model tabulated or auto",
                    behavior.name, learner.type()));
  const bool compact =
      options.model == "compact" || (options.model == "auto" && tabulatedBytes > options.maxMemoryBytes && canCompact);
  const double needed = compact ? compactBytes : tabulatedBytes;
  // A learned opponent's states multiply the grid: say by how much.
  const TrackedOpponent* tracked = behavior.environment->as<TrackedOpponent>();
  const std::size_t opponentStates = tracked ? tracked->opponentStates() : 0;
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
        "({} model and Q tables{}); expected at most {} ({}): use a coarser grid{}{}",
        behavior.name, behavior.discretizer->type(), vertices > behavior.discretizer->vertexCount() ? "up to " : "",
        vertices, opponentNote, model.actionCount(), humanBytes(needed), compact ? "compact" : "tabulated",
        heldText(learner.extraTables(), selfPlayTables, rounds), humanBytes(options.maxMemoryBytes), options.limitName,
        options.limitRaisable && !compact && canCompact && compactBytes <= options.maxMemoryBytes
            ? fmt::format(", --model compact (about {})", humanBytes(compactBytes))
            : "",
        options.limitRaisable ? fmt::format(", or raise {}", options.limitName) : ""));
  if (compact && options.model == "auto" && log)
    log(
        fmt::format("train {}: the tabulated model and tables would need about {}, over {} {}: using "
                    "the compact model (about {}; same tables, slower backups)",
                    behavior.name, humanBytes(tabulatedBytes), options.limitName, humanBytes(options.maxMemoryBytes),
                    humanBytes(compactBytes)));
  return compact;
}

// One training: the session, the bundle being filled, and the report.
class TrainRun {
 public:
  // `speaks`: this process reports (rank 0 of an MPI job, or the only one); `saves`: and
  // writes the bundle and checkpoints.
  TrainRun(const TrainSettings& settings, const TrainHooks& hooks, const Session& session, fs::path out, bool speaks)
      : settings_(settings),
        hooks_(hooks),
        session_(session),
        model_(session.model()),
        out_(std::move(out)),
        speaks_(speaks),
        saves_(speaks && settings.save),
        log_([&hooks](const std::string& m) {
          if (hooks.log) hooks.log(m);
        }) {
    if (settings.learner && settings.save)
      throw Error("training with a learner other than the scenario's: expected the tables returned, not saved");
  }

  // `given`: a behaviour the caller built (trainBehavior()) to train instead of the
  // session's own of that name.
  // `builtFrom`: the scenario it was built from (its self-play rounds are built from it).
  Trained run(const Behavior* given = nullptr, const Scenario* builtFrom = nullptr) {
    const std::vector<Behavior>& all = session_.behaviors;
    const GraphResult& graph = session_.graph;
    bundle_.graphKey = graph.key;
    bundle_.provenance = trainingProvenance(session_);
    const std::set<std::string> finished =
        settings_.save && !given ? keepCurrentTables(out_, settings_.resume, all, model_, graph.key, bundle_, log_)
                                 : std::set<std::string>();
    report_ = {{"scenario", session_.scenario.path.string()},
               {"policy", out_.string()},
               {"graph_key", graph.key},
               {"behaviors", json::object()}};
    if (given) {
      compactModel_[given->name] = choosesCompactModel(*given, learnerOf(*given), model_, settings_, log_);
      wanted_.push_back(given->name);
      trainBehavior(*given, all, *builtFrom);
      return {std::move(bundle_), std::move(report_), std::move(refined_)};
    }
    for (const Behavior& behavior : all)
      if (settings_.behavior.empty() || behavior.name == settings_.behavior) wanted_.push_back(behavior.name);
    if (wanted_.empty() && !settings_.behavior.empty())
      requireBehavior(session_.scenario, settings_.behavior);  // says which there are
    // Every behaviour's size is checked before any is trained.
    for (const Behavior& behavior : all)
      if (isWanted(behavior))
        compactModel_[behavior.name] = choosesCompactModel(behavior, learnerOf(behavior), model_, settings_, log_);
    for (const Behavior& behavior : all) {
      if (!isWanted(behavior)) continue;
      if (finished.count(behavior.name) != 0) {
        log_(fmt::format("resume: {}: already trained in {}, kept", behavior.name, out_.string()));
        report_["kept"].push_back(behavior.name);
        // A run killed after its bundle was in place may have left its checkpoints.
        checkpoints_.push_back(checkpointDirectory(out_, behavior.name));
        continue;
      }
      trainBehavior(behavior, all, session_.scenario);
    }
    if (bundle_.provenance.contains("unfinished")) bundle_.provenance.erase("unfinished");
    if (saves_) {
      savePolicyBundle(out_, bundle_);
      for (const fs::path& dir : checkpoints_) removeCheckpoint(dir);
      log_(fmt::format("policy: {}", out_.string()));
    }
    return {std::move(bundle_), std::move(report_), std::move(refined_)};
  }

 private:
  bool isWanted(const Behavior& behavior) const {
    return std::find(wanted_.begin(), wanted_.end(), behavior.name) != wanted_.end();
  }
  const Learner& learnerOf(const Behavior& behavior) const {
    return settings_.learner ? *settings_.learner : *behavior.learner;
  }

  // Self-play rounds: round 1 against the opponent the scenario names, round k
  // against round k - 1's table, or with `against: average` greedily on the mean of rounds
  // 1..k - 1's tables (fictitious self-play answers the mixture of every earlier strategy;
  // a greedy player on the mean of their values is its deterministic stand-in, so the
  // transition stays one successor per action and vertex). Each round's table is kept, the
  // last under the behaviour's own name, the others as NAME-roundK. Each round trains on an
  // environment of its own: round 1 on `behavior` as it was built, round k on the behaviour
  // built again from `builtFrom` whose opponent plays the earlier rounds' table, so that
  // nothing changes a model once built (`behavior` and the session's stay as they were).
  void trainBehavior(const Behavior& behavior, const std::vector<Behavior>& all, const Scenario& builtFrom) {
    const SelfPlayOpponent* selfPlay = std::as_const(*behavior.environment).as<SelfPlayOpponent>();
    const int rounds = selfPlay ? selfPlay->rounds() : 1;
    const bool average = selfPlay && selfPlay->roundsAgainstAverage();
    std::shared_ptr<const QTable> previous, mean;
    std::vector<Behavior> rebuilt;  // the round's own behaviour, rounds 2 on
    json roundsReport = json::array();
    for (int round = 1; round <= rounds; ++round) {
      const std::string label = round < rounds ? fmt::format("{}-round{}", behavior.name, round) : behavior.name;
      if (rounds > 1) {
        const std::string against = !previous              ? ""
                                    : average && round > 2 ? fmt::format("rounds 1-{} mean", round - 1)
                                                           : fmt::format("round {}", round - 1);
        log_(fmt::format(
            "train {}: self-play round {} of {}, against {}", behavior.name, round, rounds,
            previous ? fmt::format("{}'s table", against) : fmt::format("the {} opponent", selfPlay->policyKey())));
        if (previous) {
          rebuilt = buildBehaviors(builtFrom, session_.plugins(), model_, session_.graph.key, behavior.name);
          Behavior& fresh = rebuilt.at(0);
          fresh.environment->as<SelfPlayOpponent>()->playPolicy(fresh.discretizer.get(), average ? mean : previous,
                                                                against);
        }
      }
      const Behavior& playing = previous ? rebuilt.at(0) : behavior;
      std::optional<TableGap> tableGap;
      auto [result, record] =
          trainRound(playing, all, label, round, rounds, average ? mean.get() : previous.get(), tableGap);
      // An adaptive learner returns the grid it refined: the table's vertices are its.
      const Discretizer& tableGrid = result.grid ? *result.grid : *playing.discretizer;
      if (result.grid) refined_[round == rounds ? behavior.name : label] = result.grid;
      if (rounds > 1) {
        // Scoring the round is reporting: rank 0's.
        if (speaks_)
          roundsReport.push_back(selfPlayRound(playing, model_, round, result.table,
                                               average ? mean.get() : previous.get(), tableGap, log_));
        record["round"] = round;
        record["rounds"] = roundsReport;
        report_["behaviors"][behavior.name]["rounds"] = roundsReport;
        if (round < rounds) {
          previous = std::make_shared<const QTable>(result.table);
          if (average) mean = meanOfRounds(mean.get(), *previous, round);
        }
      }
      bundle_.behaviors[round == rounds ? behavior.name : label] = PolicyBehavior{
          behavior.key,          record, std::move(result.table), vertexPositions(tableGrid), tableGrid.type(),
          tableGrid.structure(), nullptr};
    }
  }

  // Tabulates the problem and trains one table (one round of self-play): the result and
  // its record for the bundle; its summary goes in the report when it is the last round.
  // Given the table the opponent played (`opponent`, rounds 2 on), also the best-response
  // gap on the grid (tableGap), while the tabulated problem is at hand.
  std::pair<TrainResult, json> trainRound(const Behavior& behavior, const std::vector<Behavior>& all,
                                          const std::string& label, int round, int rounds, const QTable* opponent,
                                          std::optional<TableGap>& tableGap) {
    const std::string roundKey = rounds > 1 ? fmt::format("{}-round{}", behavior.key, round) : behavior.key;
    const Problem problem = behavior.problem(model_);
    const auto tabulateStart = Clock::now();
    const bool compact = compactModel_.at(behavior.name);
    // A learner that tabulates itself (each MPI rank its share) gets the model's frame only.
    const Learner& learner = learnerOf(behavior);
    const bool itself = !compact && learner.tabulatesItself();
    if (const int ranks = launchedProcess().size; ranks > 1 && !learner.tabulatesItself())
      log_(
          fmt::format("train {}: {} runs in one process: the other {} ranks of this MPI job repeat it and keep "
                      "nothing (mpi_value_iteration shares the work)",
                      label, learner.type(), ranks - 1));
    GridModel grid;
    try {
      grid = compact  ? GridModel::buildCompact(problem, threads_, stop_)
             : itself ? GridModel::frame(problem)
                      : GridModel::build(problem, threads_, stop_);
    } catch (const TrainInterrupted& stop) {  // stopped while tabulating
      if (!saves_) throw;
      trainingInterrupted(session_.options, settings_, out_, bundle_, wanted_, behavior.name, stop,
                          checkpointDirectory(out_, label));
    }
    const double tabulateSeconds = since(tabulateStart);
    if (itself)
      log_(fmt::format("train {}: {} on a {} grid ({} vertices) x {} actions, tabulated by the learner", label,
                       learner.type(), behavior.discretizer->type(), behavior.discretizer->vertexCount(),
                       model_.actionCount()));
    else
      log_(fmt::format("train {}: {} on a {} grid ({} vertices) x {} actions, {} tabulated in {:.2f} s ({} MB)", label,
                       learner.type(), behavior.discretizer->type(), behavior.discretizer->vertexCount(),
                       model_.actionCount(), compact ? "rewards (compact model)" : "problem", tabulateSeconds,
                       grid.bytes() / 1000000));

    DirectoryCheckpointer directory(checkpointDirectory(out_, label), roundKey, model_,
                                    behavior.discretizer->vertexCount(), hooks_.log);
    if (!settings_.resume && saves_) directory.remove();
    CrashTestCheckpointer checkpointer(directory, behavior.name, hooks_.log, stop_);
    if (saves_) checkpoints_.push_back(directory.directory());
    std::optional<TrainResult> trained;
    std::unique_ptr<TrainListener> listener = hooks_.listen ? hooks_.listen(behavior, all, session_.graph) : nullptr;
    {
      ProgressReporter progress(label, hooks_.progressBar, hooks_.progressLines, hooks_.log, listener.get());
      try {
        trained = learner.train(
            {problem, grid, &progress, saves_ ? &checkpointer : nullptr, threads_, stop_, round < rounds});
      } catch (const TrainInterrupted& stop) {
        if (!saves_) throw;
        trainingInterrupted(session_.options, settings_, out_, bundle_, wanted_, behavior.name, stop,
                            directory.directory());
      }
    }
    if (settings_.resume && saves_ && !checkpointer.resumed())
      log_(fmt::format("resume: {}: no checkpoint to continue from, trained from the start", behavior.name));
    TrainResult& result = *trained;
    // Rank 0 alone reports; a learner that tabulated its own share has no model here, an
    // adaptive learner's table is not on the problem's grid, and the gap needs the problem's
    // optimum: a value iteration that converged (Q-learning's table is not one).
    const bool optimum = result.stats.is_object() && result.stats.value("converged", false);
    if (opponent && speaks_ && !itself && !result.grid && grid.hanging.empty() && optimum)
      tableGap = bestResponseGapOnGrid(grid, model_, result.table, *opponent, threads_);

    const Discretizer& tableGrid = result.grid ? *result.grid : *behavior.discretizer;
    const json summary = tableSummary(learner, result, tableGrid, model_.actionCount(), tabulateSeconds);
    if (round == rounds) {
      report_["behaviors"][behavior.name] = summary;
      report_["behaviors"][behavior.name]["model"] = compact ? "compact" : "tabulated";
      report_["behaviors"][behavior.name]["model_bytes"] = grid.bytes();
    }
    json record = tableRecord(summary, behavior, tableGrid, result.curve, listener.get());
    log_(fmt::format("train {}: {} updates in {:.2f} s ({}updates/s), Bellman residual {:.3g}", label, result.updates,
                     result.seconds, humanCount(summary.at("updates_per_second").get<double>()), result.finalResidual));
    return {std::move(result), std::move(record)};
  }

  const TrainSettings& settings_;
  const TrainHooks& hooks_;
  const Session& session_;
  const StateActionModel& model_;
  const fs::path out_;
  const bool speaks_, saves_;
  const Log log_;
  std::atomic<bool> ownStop_{false};
  std::atomic<bool>* const stop_ = hooks_.stop ? hooks_.stop : &ownStop_;
  const unsigned threads_ = defaultThreadCount();
  PolicyBundle bundle_;
  json report_;
  std::vector<std::string> wanted_;
  std::map<std::string, bool> compactModel_;
  std::vector<fs::path> checkpoints_;
  std::map<std::string, std::shared_ptr<const Discretizer>> refined_;
};

// Under an MPI launcher (`mpirun -np K mgrl train`), every process trains, a distributed
// learner's ranks together, and rank 0 alone writes (the bundle, checkpoints) and speaks;
// the others read the same files and stay silent: only the stop flag is kept.
TrainHooks heardHere(const TrainHooks& hooks, bool speaks) {
  if (speaks) return hooks;
  TrainHooks silent;
  silent.stop = hooks.stop;
  return silent;
}

}  // namespace

Trained trainScenario(const Session& session, const TrainSettings& settings, const TrainHooks& given) {
  const bool speaks = launchedProcess().rank == 0;
  const TrainHooks hooks = heardHere(given, speaks);
  const fs::path out = settings.save ? bundleFolder(settings, session.options, session.scenario) : fs::path();
  TrainRun run(settings, hooks, session, out, speaks);
  return run.run();
}

Trained trainBehavior(const Session& session, const Behavior& behavior, const Scenario& builtFrom,
                      const TrainSettings& settings, const TrainHooks& given) {
  if (settings.save)
    throw Error(fmt::format("training {} as given: expected its table returned, not saved", behavior.name));
  const bool speaks = launchedProcess().rank == 0;
  const TrainHooks hooks = heardHere(given, speaks);
  TrainSettings one = settings;
  one.behavior = behavior.name;
  TrainRun run(one, hooks, session, fs::path(), speaks);
  return run.run(&behavior, &builtFrom);
}

void checkTrainingFits(const Behavior& behavior, const StateActionModel& model, const TrainSettings& settings) {
  choosesCompactModel(behavior, settings.learner ? *settings.learner : *behavior.learner, model, settings, nullptr);
}

}  // namespace mgrl
