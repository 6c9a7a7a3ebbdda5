#pragma once
/// \file
/// Training checkpoints on disk: a Checkpointer (mgrl/learning/learner.hpp) keeping the last state
/// a learner saved in a directory, written as a bundle (mgrl/core/bundle.hpp) so a crash during
/// a save leaves the previous checkpoint or the new one, never half of one:
///
///     state.json  {"format": "mgrl.checkpoint", "version": 2, "key": "<run key>",
///                  "state": {...the learner's JSON}, "table": {"file": "table.npy", ...},
///                  "hash": "<xxh64 hex of all the other members>"}
///     table.npy   float32 (actions, vertices) = QTable::actionMajor()
///
/// The "hash" is manifestHash() (mgrl/core/bundle.hpp): one changed digit of the learner's
/// state (its update count, its random generator) would otherwise resume a different run.
/// Version 2 added it.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// The state file's "format" and "version"; a checkpoint with others is ignored.
inline constexpr std::string_view kCheckpointFormatName = "mgrl.checkpoint";
inline constexpr int kCheckpointFormatVersion = 2;
/// The checkpoint's two files in its directory (the layout above).
inline constexpr std::string_view kCheckpointStateFile = "state.json";
inline constexpr std::string_view kCheckpointTableFile = "table.npy";

/// Keeps one checkpoint in a directory. A checkpoint is only resumed by a run with the
/// same `key` (the caller's hash of the problem and learner settings); anything else
/// there is reported through the log and ignored, so training starts over instead of
/// failing.
class DirectoryCheckpointer final : public Checkpointer {
 public:
  /// Checkpoints at `dir` for tables of `model`'s actions over `vertexCount` vertices.
  /// `log` receives one line per ignored checkpoint (may be empty). Touches no file.
  DirectoryCheckpointer(std::filesystem::path dir, std::string key, const StateActionModel& model,
                        std::size_t vertexCount, WarningSink log);

  /// Replaces the checkpoint with `state` and `table`, atomically (writeBundleDirectory()).
  /// Throws mgrl::Error if `table` does not have the model's actions and vertexCount
  /// vertices, if `state` holds invalid UTF-8, if `dir` is something other than a
  /// checkpoint or an empty directory, or on any I/O failure.
  void save(const nlohmann::json& state, const QTable& table) override;

  /// The saved state, with `table` (of the model's actions and vertexCount vertices) set
  /// to the saved values; std::nullopt, leaving `table` unchanged, if there is no
  /// directory, or, after one line to the log starting with the path concerned and ending
  /// "; ignoring the checkpoint", if the checkpoint is unreadable, damaged (size or hash
  /// mismatch, of the table or of state.json), of another format or version, made for
  /// another key, or of another table shape. Never throws for a bad checkpoint; throws
  /// mgrl::Error only if `table` itself has the wrong dimensions.
  std::optional<nlohmann::json> load(QTable& table) override;

  /// load(), also ignoring (with the same log line, `check`'s message naming state.json)
  /// a checkpoint whose state `check` rejects; `check` runs before `table` is touched.
  /// An empty `check` accepts any state.
  std::optional<nlohmann::json> loadChecked(QTable& table, const StateCheck& check) override;

  /// Deletes the checkpoint directory (after a finished run, or before a run that starts
  /// over), and what killed writers left beside it (staleSiblings()), ignoring errors. A
  /// directory that holds no state.json and is not empty is not a checkpoint and is left
  /// alone.
  void remove();

  const std::filesystem::path& directory() const { return dir_; }

 private:
  void requireTableShape(const QTable& table) const;

  std::filesystem::path dir_;
  std::string key_;
  std::size_t actionCount_;
  std::size_t vertexCount_;
  WarningSink log_;
};

}  // namespace mgrl
