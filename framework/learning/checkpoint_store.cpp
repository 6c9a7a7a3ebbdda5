#include "mgrl/learning/checkpoint_store.hpp"

#include <system_error>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/bundle.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using nlohmann::json;

DirectoryCheckpointer::DirectoryCheckpointer(fs::path dir, std::string key, const StateActionModel& model,
                                             std::size_t vertexCount, WarningSink log)
    // "run/checkpoint/" names the same directory as "run/checkpoint".
    : dir_(dir.has_filename() ? std::move(dir) : dir.parent_path()),
      key_(std::move(key)),
      actionCount_(model.actionCount()),
      vertexCount_(vertexCount),
      log_(std::move(log)) {}

void DirectoryCheckpointer::requireTableShape(const QTable& table) const {
  if (table.actionCount() != actionCount_ || table.vertexCount() != vertexCount_)
    throw Error(fmt::format("{}: expected a Q table of {} actions x {} vertices, found {} x {}", dir_.string(),
                            actionCount_, vertexCount_, table.actionCount(), table.vertexCount()));
}

void DirectoryCheckpointer::save(const json& state, const QTable& table) {
  requireTableShape(table);
  EncodedArray array =
      encodeBundleArray<float>(std::string(kCheckpointTableFile), table.actionMajor(), {actionCount_, vertexCount_});
  json manifest = {{"format", std::string(kCheckpointFormatName)},
                         {"version", kCheckpointFormatVersion},
                         {"key", key_},
                         {"state", state},
                         {"table", std::move(array.entry)}};
  std::string text;
  try {
    // The learner's state decides the rest of the run: sealed, so a changed digit is noticed.
    manifest["hash"] = manifestHash(manifest);
    text = manifest.dump(2) + "\n";
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: state: expected valid UTF-8 strings, found {}", dir_.string(), e.what()));
  }
  writeBundleDirectory(dir_, {std::move(array.file)}, text, "checkpoint", kCheckpointStateFile);
}

std::optional<json> DirectoryCheckpointer::load(QTable& table) { return loadChecked(table, {}); }

std::optional<json> DirectoryCheckpointer::loadChecked(QTable& table, const StateCheck& check) {
  requireTableShape(table);
  std::error_code ec;
  recoverBundleDirectory(dir_, kCheckpointStateFile);  // what a killed writer left
  const fs::file_status status = fs::status(dir_, ec);
  if (status.type() == fs::file_type::not_found) return std::nullopt;

  // A checkpoint only saves time: whatever is wrong with it, say so and start over.
  const fs::path statePath = dir_ / kCheckpointStateFile;
  const ManifestReader reader(statePath.string());
  std::string reason;
  try {
    if (ec) throw Error(fmt::format("{}: cannot read: {}", dir_.string(), ec.message()));
    if (!fs::is_directory(status))
      throw Error(fmt::format("{}: expected a checkpoint directory, found another kind of file", dir_.string()));
    if (!fs::exists(statePath, ec))
      throw Error(fmt::format("{}: expected the state of a checkpoint, found no file", reader.source()));
    const json manifest = readManifestObject(statePath);
    const std::string format = reader.string(manifest, "", "format");
    const json& version = reader.member(manifest, "", "version");
    if (format != kCheckpointFormatName || version != kCheckpointFormatVersion)
      throw Error(fmt::format("{}: expected format '{}' version {}, found format {} version {}", reader.source(),
                              kCheckpointFormatName, kCheckpointFormatVersion, quoteToken(format),
                              quoteToken(version.dump(-1, ' ', false, json::error_handler_t::replace))));
    // Before anything else is read from it: every value below is then as saved.
    checkManifestHash(manifest, reader);
    const std::string key = reader.string(manifest, "", "key");
    if (key != key_)
      throw Error(fmt::format("{}: expected key {}, found {} (a checkpoint of other inputs or settings)",
                              reader.source(), quoteKey(key_), quoteKey(key)));
    for (const auto& item : manifest.items())
      if (item.key() != "format" && item.key() != "version" && item.key() != "key" && item.key() != "state" &&
          item.key() != "table" && item.key() != "hash")
        throw Error(fmt::format("{}: expected only the keys format, version, key, state, table, hash, found '{}'",
                                reader.source(), item.key()));
    json state = reader.member(manifest, "", "state");
    // A state the learner cannot use is as damaged as a bad hash; checked before the
    // table is touched, so ignoring the checkpoint leaves the caller's table as it was.
    if (check) check(state, reader);

    std::vector<std::size_t> shape;
    const std::vector<float> values =
        loadBundleArray<float>(dir_, reader, manifest, "", "table", kCheckpointTableFile, &shape);
    if (shape != std::vector<std::size_t>{actionCount_, vertexCount_})
      throw Error(fmt::format("{}: expected shape ({}, {}) (actions, vertices), found {}",
                              (dir_ / kCheckpointTableFile).string(), actionCount_, vertexCount_, formatShape(shape)));
    table.setActionMajor(values);
    return state;
  } catch (const Error& e) {
    reason = e.what();
  } catch (const json::exception& e) {
    reason = fmt::format("{}: {}", reader.source(), e.what());
  } catch (const fs::filesystem_error& e) {
    reason = fmt::format("{}: {}", dir_.string(), e.what());
  }
  if (log_) log_(fmt::format("{}; ignoring the checkpoint", reason));
  return std::nullopt;
}

void DirectoryCheckpointer::remove() {
  std::error_code ec;
  // What killed writers left beside it goes too (only a dead process's): a whole checkpoint
  // in a temporary would otherwise be put back by the next load's recovery, and a run that
  // starts over would continue from it (as the kill tests found).
  for (const StaleSibling& stale : staleSiblings(dir_)) fs::remove_all(stale.path, ec);
  if (!fs::is_directory(fs::symlink_status(dir_, ec))) return;
  // Never delete a directory that is not a checkpoint (a mistyped path).
  if (!fs::exists(dir_ / kCheckpointStateFile, ec) && !fs::is_empty(dir_, ec)) return;
  fs::remove_all(dir_, ec);
}

}  // namespace mgrl
