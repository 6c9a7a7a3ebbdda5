#pragma once
/// \file
/// What training writes into the policy bundle (train_bundle.cpp): where it goes (declared
/// in training.hpp: bundleFolder()), its provenance, each table's record, the tables kept
/// from the bundle already there, and a stopped run's partial bundle. Not for other code:
/// include mgrl/session/training.hpp.
#include <cstddef>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/session/training.hpp"

namespace mgrl {

/// The self-play rounds a behaviour trains (SelfPlayOpponent::rounds()); 1 for an
/// environment without an opponent that plays policy tables.
int selfPlayRounds(const Behavior& b);

/// Tables already in the bundle at `out` that are still current (same key: the same
/// settings on the same graph, so the same table) go into `bundle`: those of other
/// behaviours when training one, those a stopped run finished when resuming, and all of them
/// until replaced. Returns the behaviours a resumed run has finished. A bundle that cannot
/// be read, or a table that no longer belongs, is left out with a warning through `log`.
std::set<std::string> keepCurrentTables(const std::filesystem::path& out, bool resume, const std::vector<Behavior>& all,
                                        const StateActionModel& model, const std::string& graphKey,
                                        PolicyBundle& bundle, const WarningSink& log);

/// A stopped run keeps what had finished: the bundle is saved to `out` with the finished
/// tables and the unfinished behaviours of `wanted` named in its provenance (so eval and
/// simulate refuse it, saying to resume, instead of taking it for a whole one), then the
/// run ends with Interrupted saying where `current`'s checkpoint is and how to continue.
[[noreturn]] void trainingInterrupted(const SessionOptions& options, const TrainSettings& settings,
                                      const std::filesystem::path& out, PolicyBundle& bundle,
                                      const std::vector<std::string>& wanted, const std::string& current,
                                      const TrainInterrupted& stop, const std::filesystem::path& checkpoint);

/// A trained table's summary, the report's entry and the start of its record: {"learner",
/// "updates", "seconds", "updates_per_second", "final_residual", "table_bytes",
/// "vertices" (of `tableGrid`, the grid the table is on), "actions", "tabulate_seconds",
/// "stats"}.
nlohmann::json tableSummary(const Learner& learner, const TrainResult& result, const Discretizer& tableGrid,
                            std::size_t actions, double tabulateSeconds);

/// The record kept with a table in the bundle: `summary` with the behaviour's "config",
/// "weight", "activation", "stance" (if it has one), the table's "grid", its learning
/// "curve" (with "curve_columns") and the listener's "snapshots" (if any).
nlohmann::json tableRecord(nlohmann::json summary, const Behavior& behavior, const Discretizer& tableGrid,
                           const std::vector<CurvePoint>& curve, const TrainListener* listener);

}  // namespace mgrl
