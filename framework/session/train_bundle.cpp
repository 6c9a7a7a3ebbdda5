// What training writes into the policy bundle (train_bundle.hpp): where it goes, its
// provenance, each table's record, the tables kept from the bundle already there, and a
// stopped run's partial bundle. The training loop and memory plan are in training.cpp.
#include "mgrl/session/train_bundle.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/files.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/session/graph_source.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/self_play.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;

fs::path bundleFolder(const TrainSettings& settings, const SessionOptions& options, const Scenario& scenario) {
  const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  fs::path out =
      settings.out.empty()
          ? defaultPolicyDirectory(cacheDir, scenario, requirePlugins(options.plugins, "SessionOptions::plugins"))
          : settings.out;
  if (!out.has_filename()) out = out.parent_path();
  std::error_code ec;
  if (out.has_parent_path()) fs::create_directories(out.parent_path(), ec);
  if (ec)
    throw Error(fmt::format("--out {}: cannot create {}: {}", out.string(), out.parent_path().string(), ec.message()));
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw Error(fmt::format("--out {}: expected a policy bundle directory or nothing, found a file", out.string()));
  // The bundle is written beside `out` and renamed into place: that folder must take a
  // new file now, not after training. The probe is `.<name>.probe-PID`.
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  if (!folderTakesNewFiles(parent, fmt::format(".{}.probe-", out.filename().string())))
    throw Error(fmt::format("--out {}: expected a folder where files can be written, found {} is not writable",
                            out.string(), parent.string()));
  return out;
}

int selfPlayRounds(const Behavior& b) {
  const SelfPlayOpponent* selfPlay = b.environment->as<SelfPlayOpponent>();
  return selfPlay ? selfPlay->rounds() : 1;
}

json trainingProvenance(const Session& session) {
  return {{"scenario", session.scenario.path.string()},
          {"scenario_name", session.scenario.name},
          {"tool", fmt::format("mgrl {}", kVersion)},
          {"sets", session.options.sets}};
}

std::set<std::string> keepCurrentTables(const fs::path& out, bool resume, const std::vector<Behavior>& all,
                                        const StateActionModel& model, const std::string& graphKey,
                                        PolicyBundle& bundle, const WarningSink& log) {
  std::set<std::string> finished;
  if (!fs::exists(out / "manifest.json")) return finished;
  try {
    PolicyBundle previous = loadPolicyBundle(out, model, graphKey);
    // A stopped run's bundle holds only finished tables (its unfinished ones are absent).
    for (auto& item : previous.behaviors) {
      // Named, not a structured binding: clang before 16 cannot capture one in the lambda.
      const std::string& name = item.first;
      auto& entry = item.second;
      // A self-play round's table (NAME-roundK) belongs to behaviour NAME.
      std::string base = name;
      if (const auto cut = name.rfind("-round"); cut != std::string::npos && cut > 0) base = name.substr(0, cut);
      const auto match = std::find_if(all.begin(), all.end(), [&](const Behavior& b) {
        return b.name == name || (b.name == base && selfPlayRounds(b) > 1);
      });
      if (match != all.end() && match->key == entry.key) {
        bundle.behaviors.emplace(name, std::move(entry));
        if (resume && match->name == name) finished.insert(name);
      } else {
        log(fmt::format("warning: dropping {}'s table from {}: the scenario {}", name, out.string(),
                        match == all.end() ? "no longer has this behaviour" : "now asks for other settings"));
      }
    }
  } catch (const Error& e) {
    log(fmt::format("warning: not keeping the behaviours already in {}: {}", out.string(), e.what()));
  }
  return finished;
}

void trainingInterrupted(const SessionOptions& options, const TrainSettings& settings, const fs::path& out,
                         PolicyBundle& bundle, const std::vector<std::string>& wanted, const std::string& current,
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
  const std::string where = stop.checkpointed() ? fmt::format("checkpoint at {} of {} actions in {}", stop.updates(),
                                                              stop.total(), checkpoint.string())
                                                : std::string("no checkpoint: it starts over");
  std::string command = fmt::format("mgrl train {}", options.scenario.string());
  if (!settings.behavior.empty()) command += fmt::format(" --behavior {}", settings.behavior);
  command += setFlags(options.sets);
  if (!settings.out.empty()) command += fmt::format(" --out {}", settings.out.string());
  throw Interrupted(fmt::format("interrupted while training {} ({}); {}; run `{} --resume` to continue", current, where,
                                keptText, command));
}

json tableSummary(const Learner& learner, const TrainResult& result, const Discretizer& tableGrid, std::size_t actions,
                  double tabulateSeconds) {
  const double rate = result.seconds > 0 ? static_cast<double>(result.updates) / result.seconds : 0;
  return {{"learner", learner.type()},
          {"updates", result.updates},
          {"seconds", result.seconds},
          {"updates_per_second", rate},
          {"final_residual", result.finalResidual},
          {"table_bytes", result.table.bytes()},
          {"vertices", tableGrid.vertexCount()},
          {"actions", actions},
          {"tabulate_seconds", tabulateSeconds},
          {"stats", result.stats}};
}

namespace {

// What every table's record says of its behaviour and grid, after `record`'s own keys.
json withBehavior(json record, const Behavior& behavior, const Discretizer& tableGrid) {
  record["config"] = behavior.config;
  record["weight"] = behavior.weight;
  record["activation"] = std::string(activationName(behavior.activation));
  if (behavior.stance >= 0) record["stance"] = behavior.stance;  // absent before stances
  record["grid"] = tableGrid.describe();
  return record;
}

}  // namespace

json tableRecord(json summary, const Behavior& behavior, const Discretizer& tableGrid,
                 const std::vector<CurvePoint>& curve, const TrainListener* listener) {
  json points = json::array();
  for (const CurvePoint& p : curve) points.push_back({p.updates, p.seconds, p.residual, p.meanResidual});
  json record = withBehavior(std::move(summary), behavior, tableGrid);
  record["curve_columns"] = {"updates", "seconds", "residual", "mean_residual"};
  record["curve"] = points;
  if (listener) {
    json snapshots = listener->record();
    if (!snapshots.is_null()) record["snapshots"] = std::move(snapshots);
  }
  return record;
}

PolicyBehavior givenTable(const Behavior& behavior, QTable table, const std::string& learner,
                          const std::string& trainedIn) {
  const Discretizer& grid = *behavior.discretizer;
  json record = withBehavior({{"learner", learner}, {"trained_in", trainedIn}}, behavior, grid);
  return PolicyBehavior{behavior.key, std::move(record), std::move(table), vertexPositions(grid),
                        grid.type(),  grid.structure(),  nullptr};
}

}  // namespace mgrl
