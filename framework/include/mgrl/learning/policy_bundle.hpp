#pragma once
/// \file
/// The policy bundle (DESIGN.md sec. 6): what `mgrl train` leaves for the controller, a
/// directory holding `manifest.json` and, per behaviour, its Q table and the grid vertices
/// the table's columns belong to, as NumPy files a student can open with `numpy.load`.
///
/// manifest.json:
///
///     {"format": "mgrl.policy", "version": 2,
///      "graph_key": "<graph cache key the tables were trained on>",
///      "provenance": {...whatever the caller records},
///      "behaviors": {"hit": {"key": "<behaviour key>", "record": {...},
///                            "table": {"file": "hit.q.npy", "dtype": "<f4",
///                                      "shape": [A, V], "bytes": size, "hash": "<xxh64>"},
///                            "vertices": {"file": "hit.vertices.npy", "dtype": "<f8",
///                                         "shape": [V, 3], ...}},
///                    ...},
///      "hash": "<xxh64 of every other member: manifestHash(), mgrl/core/bundle.hpp>"}
///
/// The "hash" seals the manifest: the graph key, each behaviour's key and record and the
/// file entries (each with its file's size and hash), so a hand-edited manifest is refused
/// on load as an altered table is. Version 1 bundles (before the seal) are refused with a
/// message to retrain: nothing in them tells an edit from what `mgrl train` wrote.
///
/// `<name>.q.npy` holds Q(v, a) with row a = action a's table over the V vertices
/// (QTable::actionMajor()); `<name>.vertices.npy` holds the vertices' positions, one row
/// each. Array entries are as in mgrl/core/bundle.hpp.
///
/// A behaviour trained on a grid with its own structure (kd_tree, Discretizer::structure())
/// also has `"grid": {"type": "kd_tree", "arrays": {"split_axis": {entry}, ...}}`, each array
/// in `<name>.grid.<array>.npy` (int32 or float64); the caller rebuilds the grid from them
/// with Discretizer::restored(), which checks their consistency.

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/discretizer.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// The manifest's "format" and "version"; loadPolicyBundle() refuses others.
inline constexpr std::string_view kPolicyFormatName = "mgrl.policy";
inline constexpr int kPolicyFormatVersion = 2;

/// One trained behaviour.
struct PolicyBehavior {
  /// Hash of everything this behaviour's table depends on (computed by the caller, which
  /// compares it to decide whether the table is still current).
  std::string key;
  /// A JSON object written as is (learner, parameters, training curve, statistics).
  nlohmann::json record = nlohmann::json::object();
  /// Saved as `<name>.q.npy`, float32 of shape (actions, vertices) = table.actionMajor().
  QTable table;
  /// (vertexCount, 3) vertex positions, row-major, saved as `<name>.vertices.npy` float64.
  std::vector<double> vertices;
  /// The grid's type and structure (Discretizer::structure()); empty for fixed grids.
  std::string gridType;
  std::vector<StructureArray> grid;
  /// Not saved: the grid rebuilt from `grid` by whoever uses the table (see policyParts in
  /// the application), kept here so that it lives as long as the table.
  std::shared_ptr<const Discretizer> restoredGrid;
};

/// Everything a policy bundle holds.
struct PolicyBundle {
  std::string graphKey;  ///< the graph cache key the tables were trained on
  /// A JSON object written as is (scenario path and name, tool version, ...).
  nlohmann::json provenance = nlohmann::json::object();
  /// By behaviour name; names are file stems, so made only of [A-Za-z0-9_-].
  std::map<std::string, PolicyBehavior> behaviors;
};

/// True if `name` can name a behaviour in a bundle: one or more of [A-Za-z0-9_-].
bool isPolicyBehaviorName(std::string_view name);

/// The grid's vertex positions as PolicyBehavior::vertices holds them: (vertexCount, 3),
/// row-major.
std::vector<double> vertexPositions(const Discretizer& grid);

/// Writes `bundle` at `dir` (see the file comment), replacing a policy bundle already there,
/// atomically as writeBundleDirectory() does (the manifest written last). Writes the same
/// bytes for the same bundle.
/// Throws mgrl::Error, writing nothing, if a behaviour name fails isPolicyBehaviorName(),
/// if a behaviour's vertices are not (table.vertexCount(), 3), if a table or vertex value
/// is not finite, if provenance or a record is not a JSON object or holds invalid UTF-8,
/// if `dir` is something other than a policy bundle or an empty directory, or on any I/O
/// failure.
void savePolicyBundle(const std::filesystem::path& dir, const PolicyBundle& bundle);

/// The hash a bundle's manifest records for `table`'s file (behaviors.NAME.table.hash):
/// two tables with the same hash are the same bytes, however they were trained.
std::string tableHash(const QTable& table);

/// Loads the bundle at `dir`, trained on the graph `model` whose cache key is `graphKey`.
/// Every table is checked to be (model.actionCount(), V) with finite values and its
/// vertices (V, 3), and every file against its size and hash in the manifest.
/// Throws mgrl::Error with one line naming the file and what was expected and found:
/// no directory (`<dir>: no policy bundle here: run `mgrl train` first (or pass --policy
/// DIR)`), a missing or malformed manifest, another format or version (version 1: written
/// before the seal), a missing "hash" or one its members do not match (`<dir>/manifest.json:
/// expected its members to hash to '<stored>' as its "hash" says, found '<computed>': the
/// manifest ... was edited after it was written; retrain with `mgrl train`), a bundle made for
/// another graph (both keys, shortened to 16 characters), a behaviour name that is not a
/// file stem, a missing, truncated or altered file, or wrong shapes or values.
PolicyBundle loadPolicyBundle(const std::filesystem::path& dir, const StateActionModel& model,
                              std::string_view graphKey);

}  // namespace mgrl
