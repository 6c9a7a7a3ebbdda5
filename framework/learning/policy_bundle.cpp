#include "mgrl/learning/policy_bundle.hpp"

#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <system_error>

#include <fmt/format.h>

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::string_view kKind = "policy bundle";
constexpr std::string_view kRetrain = "retrain with `mgrl train`";

std::string tableFile(std::string_view name) { return fmt::format("{}.q.npy", name); }
std::string verticesFile(std::string_view name) { return fmt::format("{}.vertices.npy", name); }
std::string structureFile(std::string_view name, std::string_view array) {
  return fmt::format("{}.grid.{}.npy", name, array);
}

template <class T>
std::optional<std::size_t> firstNonFinite(std::span<const T> values) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i])) return i;
  return std::nullopt;
}

std::string dumpForMessage(const json& value) {
  return quoteToken(value.dump(-1, ' ', false, json::error_handler_t::replace));
}

// The manifest's "hash" (manifestHash(): every other member, the files' entries with their
// own sizes and hashes included) must match, so an edited graph key, behaviour key or record
// is refused like an altered table. One line: the file, both digests, what to do.
void checkSeal(const json& manifest, const ManifestReader& reader) {
  const auto stored = manifest.find("hash");
  if (stored == manifest.end())
    throw Error(fmt::format("{}: expected a \"hash\" member sealing the manifest, found none (removed by hand?): {}",
                            reader.source(), kRetrain));
  if (!stored->is_string())
    throw Error(fmt::format("{}: hash: expected a string of 16 hex digits, found {}: {}", reader.source(),
                            dumpForMessage(*stored), kRetrain));
  std::string actual;
  try {
    actual = manifestHash(manifest);
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: expected valid UTF-8 strings, found {}: {}", reader.source(), e.what(), kRetrain));
  }
  if (actual != stored->get<std::string>())
    throw Error(fmt::format("{}: expected its members to hash to {} as its \"hash\" says, found {}: the manifest "
                            "(graph key, behaviour keys, records or file entries) was edited after it was written; "
                            "{}",
                            reader.source(), quoteToken(stored->get<std::string>()), quoteToken(actual), kRetrain));
}

}  // namespace

std::vector<double> vertexPositions(const Discretizer& grid) {
  std::vector<double> out;
  out.reserve(3 * grid.vertexCount());
  for (std::size_t v = 0; v < grid.vertexCount(); ++v) {
    const Eigen::Vector3d p = grid.vertexPosition(v);
    out.insert(out.end(), {p.x(), p.y(), p.z()});
  }
  return out;
}

bool isPolicyBehaviorName(std::string_view name) {
  if (name.empty()) return false;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

void savePolicyBundle(const fs::path& dirArgument, const PolicyBundle& bundle) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  const std::string source = dir.string();
  if (!bundle.provenance.is_object())
    throw Error(fmt::format("{}: provenance: expected a JSON object, found {}", source,
                            dumpForMessage(bundle.provenance)));

  // Everything is encoded and checked before touching the disk, so a refusal writes nothing.
  std::vector<BundleFile> files;
  json behaviors = json::object();
  for (const auto& [name, behavior] : bundle.behaviors) {
    if (!isPolicyBehaviorName(name))
      throw Error(fmt::format("{}: behaviors: expected names made of letters, digits, '_' and '-' (they name files), "
                              "found {}",
                              source, quoteToken(name)));
    const std::string here = fmt::format("{}: behaviors.{}", source, name);
    if (!behavior.record.is_object())
      throw Error(fmt::format("{}.record: expected a JSON object, found {}", here, dumpForMessage(behavior.record)));
    const QTable& table = behavior.table;
    const std::size_t vertexCount = table.vertexCount();
    if (vertexCount == 0) throw Error(fmt::format("{}.table: expected a Q table over at least one vertex, found none", here));
    if (behavior.vertices.size() != 3 * vertexCount)
      throw Error(fmt::format("{}.vertices: expected {} values (3 per vertex of the Q table), found {}", here,
                              3 * vertexCount, behavior.vertices.size()));
    const std::vector<float> q = table.actionMajor();
    if (const auto i = firstNonFinite<float>(q))
      throw Error(fmt::format("{}.table: expected finite Q values, found {} at action {}, vertex {}", here, q[*i],
                              *i / vertexCount, *i % vertexCount));
    if (const auto i = firstNonFinite<double>(behavior.vertices))
      throw Error(fmt::format("{}.vertices: expected finite positions, found {} at vertex {}", here,
                              behavior.vertices[*i], *i / 3));

    EncodedArray tableArray = encodeBundleArray<float>(tableFile(name), q, {table.actionCount(), vertexCount});
    EncodedArray verticesArray = encodeBundleArray<double>(verticesFile(name), behavior.vertices, {vertexCount, 3});
    behaviors[name] = {{"key", behavior.key},
                       {"record", behavior.record},
                       {"table", std::move(tableArray.entry)},
                       {"vertices", std::move(verticesArray.entry)}};
    files.push_back(std::move(tableArray.file));
    files.push_back(std::move(verticesArray.file));
    if (!behavior.grid.empty()) {
      json arrays = json::object();
      for (const StructureArray& array : behavior.grid) {
        if (!isPolicyBehaviorName(array.name) || arrays.contains(array.name))
          throw Error(fmt::format("{}.grid: expected distinct array names made of letters, digits, '_' and '-', "
                                  "found {}",
                                  here, quoteToken(array.name)));
        EncodedArray encoded =
            array.integer
                ? encodeBundleArray<std::int32_t>(structureFile(name, array.name), array.ints, array.shape)
                : encodeBundleArray<double>(structureFile(name, array.name), array.reals, array.shape);
        arrays[array.name] = std::move(encoded.entry);
        files.push_back(std::move(encoded.file));
      }
      behaviors[name]["grid"] = {{"type", behavior.gridType}, {"arrays", std::move(arrays)}};
    }
  }

  json manifest = {
      {"format", std::string(kPolicyFormatName)},
      {"version", kPolicyFormatVersion},
      {"graph_key", bundle.graphKey},
      {"provenance", bundle.provenance},
      {"behaviors", std::move(behaviors)},
  };
  std::string manifestText;
  try {
    // Sealed: the graph key, each behaviour's key and record and the files' entries (their
    // sizes and hashes) are checked on load, so a hand edit is refused, not trusted.
    manifest["hash"] = manifestHash(manifest);
    manifestText = manifest.dump(2) + "\n";
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: expected valid UTF-8 strings in keys, provenance and records, found {}", source,
                            e.what()));
  }
  writeBundleDirectory(dir, files, manifestText, kKind);
}

std::string tableHash(const QTable& table) {
  const std::vector<float> q = table.actionMajor();
  return encodeBundleArray<float>("table.npy", q, {table.actionCount(), table.vertexCount()}).entry.at("hash");
}

PolicyBundle loadPolicyBundle(const fs::path& dirArgument, const StateActionModel& model, std::string_view graphKey) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  recoverBundleDirectory(dir, "manifest.json");  // what a killed writer left
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (status.type() == fs::file_type::not_found)
    throw Error(fmt::format("{}: no policy bundle here: run `mgrl train` first (or pass --policy DIR)", dir.string()));
  if (ec) throw Error(fmt::format("{}: cannot read: {}", dir.string(), ec.message()));
  if (!fs::is_directory(status))
    throw Error(fmt::format("{}: expected a policy bundle directory, found another kind of file", dir.string()));

  const fs::path manifestPath = dir / "manifest.json";
  const ManifestReader reader(manifestPath.string());
  if (!fs::exists(manifestPath, ec))
    throw Error(fmt::format("{}: expected the manifest of a policy bundle, found no file (is {} the output of "
                            "`mgrl train`?)",
                            reader.source(), dir.string()));
  try {
    const json manifest = readManifestObject(manifestPath);
    const std::string format = reader.string(manifest, "", "format");
    const json& version = reader.member(manifest, "", "version");
    if (format != kPolicyFormatName || version != kPolicyFormatVersion)
      throw Error(fmt::format("{}: expected format '{}' version {}, found format {} version {}{}: {}", reader.source(),
                              kPolicyFormatName, kPolicyFormatVersion, quoteToken(format), dumpForMessage(version),
                              format == kPolicyFormatName && version == 1
                                  ? " (written before policy manifests were sealed by a hash, so an edit to its graph "
                                    "key or records could not be noticed)"
                                  : "",
                              kRetrain));
    // Before anything else is read from it: every value below is then as `mgrl train` wrote it.
    checkSeal(manifest, reader);
    const std::string bundleGraphKey = reader.string(manifest, "", "graph_key");
    if (bundleGraphKey != graphKey)
      throw Error(fmt::format("{}: expected graph key {}, found {}: the policy was made for another graph; {}",
                              reader.source(), quoteKey(graphKey), quoteKey(bundleGraphKey), kRetrain));
    for (const auto& item : manifest.items())
      if (item.key() != "format" && item.key() != "version" && item.key() != "graph_key" &&
          item.key() != "provenance" && item.key() != "behaviors" && item.key() != "hash")
        throw Error(fmt::format("{}: expected only the keys format, version, graph_key, provenance, behaviors, hash, "
                                "found '{}'",
                                reader.source(), item.key()));

    PolicyBundle bundle;
    bundle.graphKey = bundleGraphKey;
    bundle.provenance = reader.object(manifest, "", "provenance", {});
    const json& behaviors = reader.object(manifest, "", "behaviors", {});
    for (const auto& item : behaviors.items()) {
      const std::string& name = item.key();
      if (!isPolicyBehaviorName(name))
        throw Error(fmt::format("{}: behaviors: expected names made of letters, digits, '_' and '-' (they name "
                                "files), found {}",
                                reader.source(), quoteToken(name)));
      const std::string path = ManifestReader::join("behaviors", name);
      const json& entry = reader.object(behaviors, "behaviors", name, {"key", "record", "table", "vertices", "grid"});
      PolicyBehavior behavior;
      behavior.key = reader.string(entry, path, "key");
      behavior.record = reader.object(entry, path, "record", {});

      // The table is read in place from the mapped file (a copy of 10 MB in fresh memory
      // was most of eval's start).
      const MappedBundleArray<float> mapped = mapBundleArray<float>(dir, reader, entry, path, "table", tableFile(name));
      const std::span<const float> q = mapped.data;
      std::vector<std::size_t> shape = mapped.shape;
      const std::string qSource = (dir / tableFile(name)).string();
      if (shape.size() != 2 || shape[0] != model.actionCount() || shape[1] == 0)
        throw Error(fmt::format("{}: expected shape ({}, V) (a row per action of the graph, V >= 1 vertices), "
                                "found {}",
                                qSource, model.actionCount(), formatShape(shape)));
      const std::size_t vertexCount = shape[1];
      if (const auto i = firstNonFinite<float>(q))
        throw Error(fmt::format("{}: expected finite Q values, found {} at action {}, vertex {}", qSource, q[*i],
                                *i / vertexCount, *i % vertexCount));

      behavior.vertices = loadBundleArray<double>(dir, reader, entry, path, "vertices", verticesFile(name), &shape);
      const std::string verticesSource = (dir / verticesFile(name)).string();
      if (shape != std::vector<std::size_t>{vertexCount, 3})
        throw Error(fmt::format("{}: expected shape ({}, 3) (a row per vertex of {}), found {}", verticesSource,
                                vertexCount, tableFile(name), formatShape(shape)));
      if (const auto i = firstNonFinite<double>(behavior.vertices))
        throw Error(fmt::format("{}: expected finite positions, found {} at vertex {}", verticesSource,
                                behavior.vertices[*i], *i / 3));

      if (entry.contains("grid")) {
        const std::string gridPath = ManifestReader::join(path, "grid");
        const json& grid = reader.object(entry, path, "grid", {"type", "arrays"});
        behavior.gridType = reader.string(grid, gridPath, "type");
        const json& arrays = reader.object(grid, gridPath, "arrays", {});
        const std::string arraysPath = ManifestReader::join(gridPath, "arrays");
        for (const auto& array : arrays.items()) {
          if (!isPolicyBehaviorName(array.key()))
            throw Error(fmt::format("{}: {}: expected names made of letters, digits, '_' and '-', found {}",
                                    reader.source(), arraysPath, quoteToken(array.key())));
          StructureArray loaded;
          loaded.name = array.key();
          loaded.source = (dir / structureFile(name, array.key())).string();
          const json& arrayEntry = reader.object(arrays, arraysPath, array.key(), {});
          loaded.integer = arrayEntry.value("dtype", json()) == json(npyDescr<std::int32_t>());
          if (loaded.integer)
            loaded.ints = loadBundleArray<std::int32_t>(dir, reader, arrays, arraysPath, array.key(),
                                                        structureFile(name, array.key()), &loaded.shape);
          else
            loaded.reals = loadBundleArray<double>(dir, reader, arrays, arraysPath, array.key(),
                                                   structureFile(name, array.key()), &loaded.shape);
          behavior.grid.push_back(std::move(loaded));
        }
      }

      behavior.table = QTable(model, vertexCount);
      behavior.table.setActionMajor(q);
      bundle.behaviors.emplace(name, std::move(behavior));
    }
    return bundle;
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: {}", reader.source(), e.what()));
  } catch (const fs::filesystem_error& e) {
    throw Error(fmt::format("{}: {}", dir.string(), e.what()));
  }
}

}  // namespace mgrl
