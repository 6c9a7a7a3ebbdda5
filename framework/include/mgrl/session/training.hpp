#pragma once
/// \file
/// Training a scenario's behaviours: the one way every front end trains (`mgrl train`,
/// `mgrl compare`, Python's `Session.train` and the tables `evaluate` trains when it finds
/// none). The memory plan and model choice, self-play rounds, checkpoints and `--resume`,
/// interruption, progress and snapshots through a listener, and the bundle's record and
/// provenance are all here, so every front end gets the same tables from the same settings.
#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/session/session.hpp"

namespace mgrl {

/// Hears one behaviour's training beside the progress report (compare's snapshot
/// evaluator, Python's callbacks): progress and snapshots as a TrainObserver, and a record
/// kept in the bundle.
class TrainListener : public TrainObserver {
 public:
  /// Kept in the behaviour's record in the policy bundle under "snapshots" (null: nothing).
  virtual nlohmann::json record() const { return nullptr; }
  /// Appended to the progress line (say, the last snapshot's success rate); "" nothing.
  virtual std::string status() const { return {}; }
};

/// Called once per behaviour (and self-play round) about to be trained, with the scenario's
/// behaviours and the graph the tables are for (both outlive the listener); may return null.
using ListenerFactory = std::function<std::unique_ptr<TrainListener>(
    const Behavior& trained, const std::vector<Behavior>& all, const GraphResult& graph)>;

/// What to train, and where the tables go.
struct TrainSettings {
  std::string behavior;          ///< only this one ("" every behaviour)
  std::filesystem::path out;     ///< the policy bundle ("" the scenario's default in the cache)
  bool save = true;              ///< write the bundle and checkpoints; false: the tables are only returned
  bool resume = false;           ///< continue from checkpoints left by a killed run
  double maxMemoryBytes = 1e18;  ///< refuse a behaviour whose training would need more
  /// The learning problem's model: "tabulated" (every transition stored, the fastest),
  /// "compact" (rewards only, a fifth of the memory, landings found per backup; same
  /// tables), or "auto": tabulated when it fits in maxMemoryBytes, else compact.
  std::string model = "auto";
  std::string limitName = "--max-memory";  ///< what sets maxMemoryBytes, as a refusal names it
  bool limitRaisable = true;               ///< a refusal may say to raise it
  /// Trains `behavior` with this learner instead of its own (null: its own). Its table
  /// then belongs to other settings than the scenario's: only with save = false.
  std::shared_ptr<const Learner> learner;
};

/// Who hears the training, and what stops it.
struct TrainHooks {
  WarningSink log;            ///< what training says, a line at a time (null: nothing)
  bool progressBar = false;   ///< a bar redrawn in place on stderr (a terminal); else a line every 10 s
  bool progressLines = true;  ///< without a bar, a progress line every 10 s through `log`
  ListenerFactory listen;     ///< null: no listener
  /// Raised (by a signal handler, another thread): the learner stops at its next safe point
  /// and saves a checkpoint; what had finished is kept. Null: only the crash-test hooks stop it.
  std::atomic<bool>* stop = nullptr;
};

/// What training made: the bundle (every table trained, and those kept from the bundle
/// already at `out`), and the report {"scenario", "policy", "graph_key", "behaviors":
/// {NAME: {"learner", "updates", "seconds", "updates_per_second", "final_residual",
/// "table_bytes", "vertices", "actions", "model", "model_bytes", "stats", "rounds"...}},
/// "kept": [NAME...]}.
struct Trained {
  PolicyBundle bundle;
  nlohmann::json report;
  /// The grids adaptive learners refined, by table name (their tables' vertices are these).
  std::map<std::string, std::shared_ptr<const Discretizer>> refined;
};

/// Trains the session's behaviours (or settings.behavior), each self-play round included,
/// and with settings.save writes the bundle atomically to settings.out (or the default).
/// Every behaviour's size is checked before any is trained. The session is not changed:
/// self-play rounds train on an environment of their own. Under an MPI launcher every
/// process calls it; a distributed learner's ranks train together and rank 0 alone writes
/// and speaks. Throws Interrupted when hooks.stop was raised (with save, after saving
/// what had finished and saying how to resume), mgrl::Error for settings that do not fit.
Trained trainScenario(const Session& session, const TrainSettings& settings, const TrainHooks& hooks = {});

/// Trains `behavior`, one the caller built on the session's graph from `builtFrom` (a
/// scenario with other settings than the session's, say: the viewer's retraining), as
/// trainScenario() trains the session's; settings.save must be false. Its self-play rounds
/// after the first train on the behaviour built again from `builtFrom`, so `behavior` is
/// not changed.
Trained trainBehavior(const Session& session, const Behavior& behavior, const Scenario& builtFrom,
                      const TrainSettings& settings, const TrainHooks& hooks = {});

/// The bundle's provenance for a training on `session`: {"scenario", "scenario_name",
/// "tool", "sets"}.
nlohmann::json trainingProvenance(const Session& session);
/// A table trained elsewhere (a Python learner) as the bundle entry training writes for
/// `behavior`: its key, its record ({"learner", "trained_in"} and the behaviour's "config",
/// "weight", "activation", "stance", "grid"), the grid's vertices and structure.
PolicyBehavior givenTable(const Behavior& behavior, QTable table, const std::string& learner,
                          const std::string& trainedIn);

/// Throws mgrl::Error, as training would before it starts, when `behavior`'s training with
/// `settings` (its learner, memory limit and model) does not fit.
void checkTrainingFits(const Behavior& behavior, const StateActionModel& model, const TrainSettings& settings);

/// The bundle's folder training writes: settings.out or the scenario's default in the
/// cache. Fails (before hours of training, not after) when it cannot be created or written.
std::filesystem::path bundleFolder(const TrainSettings& settings, const SessionOptions& options,
                                   const Scenario& scenario);

/// Training stopped by its stop flag after keeping what it could; the message says how to
/// continue. The command line exits with 130 for it.
class Interrupted : public Error {
 public:
  using Error::Error;
};

}  // namespace mgrl
