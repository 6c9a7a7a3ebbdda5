#include "mgrl/graph_cache.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <system_error>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/error.hpp"
#include "mgrl/hash.hpp"
#include "mgrl/motion_io.hpp"
#include "mgrl/npy.hpp"

namespace mgrl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---------------------------------------------------------------------------------------
// The arrays of a bundle, listed once for saving and loading. Hits are an array of
// structs in the model and two arrays in the bundle, so they are handled beside this.

template <class Model, class Visitor>
void forEachArray(Model& m, Visitor&& visit) {
  visit("clip_offset", m.clipOffset, 1);
  visit("component_frames", m.componentFrames, 1);
  visit("transitions", m.transitions, 2);
  visit("transition_distance", m.transitionDistance, 1);
  visit("state_frame", m.stateFrame, 1);
  visit("action_from", m.actionFrom, 1);
  visit("action_to", m.actionTo, 1);
  visit("action_frame_begin", m.actionFrameBegin, 1);
  visit("action_displacement", m.actionDisplacement, 3);
  visit("state_action_begin", m.stateActionBegin, 1);
  visit("action_frames", m.actionFrames, 1);
  visit("frame_root", m.frameRoot, 3);
  visit("frame_centroid", m.frameCentroid, 3);
  visit("frame_enters_transition", m.frameEntersTransition, 1);
  visit("action_hit_begin", m.actionHitBegin, 1);
}

constexpr std::size_t kHitIndexColumns = 3;  // action, offset, hand
constexpr std::size_t kHitValueColumns = 4;  // x, y, z, weight

std::vector<std::size_t> shapeOf(std::size_t size, std::size_t columns) {
  if (columns == 1) return {size};
  return {size / columns, columns};
}

std::string shapeText(const std::vector<std::size_t>& shape) {
  if (shape.size() == 1) return fmt::format("({},)", shape[0]);
  return fmt::format("({})", fmt::join(shape, ", "));
}

// ---------------------------------------------------------------------------------------
// Saving

struct ArrayFile {
  std::string name;
  std::string bytes;
};

void writeWholeFile(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (out) out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (out) out.flush();
  if (!out) throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(errno)));
}

// A name beside `dir` that nothing has: `dir.<tag>-<pid>-<counter>`. With `create`, the
// directory is made by the same call that proves the name free, so two writers never share it.
fs::path freshSibling(const fs::path& dir, std::string_view tag, bool create) {
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0; attempt < 1000; ++attempt) {
    const fs::path candidate =
        dir.parent_path() / fmt::format("{}.{}-{}-{}", dir.filename().string(), tag, ::getpid(), counter++);
    std::error_code ec;
    if (create) {
      if (fs::create_directory(candidate, ec)) return candidate;
      if (ec) throw Error(fmt::format("{}: cannot create {}: {}", dir.string(), candidate.string(), ec.message()));
    } else if (!fs::exists(fs::symlink_status(candidate, ec))) {
      return candidate;
    }
  }
  throw Error(fmt::format("{}: expected a free name for a {} directory beside it, found none", dir.string(), tag));
}

void renameOrThrow(const fs::path& from, const fs::path& to, std::string_view source) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) throw Error(fmt::format("{}: cannot rename {} to {}: {}", source, from.string(), to.string(), ec.message()));
}

// ---------------------------------------------------------------------------------------
// Loading: every read of the manifest checks the type, so a hand-edited or damaged manifest
// produces a message naming the member instead of a json exception.

class ManifestReader {
 public:
  explicit ManifestReader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(std::string_view path, std::string_view expected, const json& found) const {
    throw Error(fmt::format("{}: {}: expected {}, found {}", source_, path, expected,
                            quoteToken(found.dump(-1, ' ', false, json::error_handler_t::replace))));
  }

  const json& object(const json& parent, std::string_view path, std::string_view key,
                     std::initializer_list<std::string_view> allowed) const {
    const json& value = member(parent, path, key);
    const std::string here = join(path, key);
    if (!value.is_object()) fail(here, "an object", value);
    for (const auto& item : value.items()) {
      bool known = false;
      for (std::string_view name : allowed) known = known || item.key() == name;
      if (!known && allowed.size() > 0)
        throw Error(fmt::format("{}: {}: expected only the keys {}, found '{}'", source_, here,
                                fmt::join(allowed, ", "), item.key()));
    }
    return value;
  }

  const json& member(const json& parent, std::string_view path, std::string_view key) const {
    const auto it = parent.find(key);
    if (it == parent.end())
      throw Error(fmt::format("{}: {}: expected the key '{}', found none", source_, path.empty() ? "manifest" : path,
                              key));
    return *it;
  }

  std::string string(const json& parent, std::string_view path, std::string_view key) const {
    const json& value = member(parent, path, key);
    if (!value.is_string()) fail(join(path, key), "a string", value);
    return value.get<std::string>();
  }

  double number(const json& parent, std::string_view path, std::string_view key) const {
    const json& value = member(parent, path, key);
    if (!value.is_number()) fail(join(path, key), "a number", value);
    return value.get<double>();
  }

  std::uint64_t unsignedInteger(const json& parent, std::string_view path, std::string_view key,
                                std::uint64_t max) const {
    const json& value = member(parent, path, key);
    if (!value.is_number_unsigned() || value.get<std::uint64_t>() > max)
      fail(join(path, key), fmt::format("an integer in [0, {}]", max), value);
    return value.get<std::uint64_t>();
  }

  static std::string join(std::string_view path, std::string_view key) {
    return path.empty() ? std::string(key) : fmt::format("{}.{}", path, key);
  }

  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

// One array: its manifest entry, the file's size and hash against it, then a strict decode.
template <NpyElement T>
std::vector<T> loadArray(const fs::path& dir, const ManifestReader& reader, const json& arrays,
                         std::string_view name, std::size_t columns) {
  const json& entry = reader.object(arrays, "arrays", name, {"file", "dtype", "shape", "bytes", "hash"});
  const std::string path = ManifestReader::join("arrays", name);
  const std::string file = reader.string(entry, path, "file");
  if (file != fmt::format("{}.npy", name))
    reader.fail(ManifestReader::join(path, "file"), fmt::format("'{}.npy'", name), entry["file"]);
  if (reader.string(entry, path, "dtype") != npyDescr<T>())
    reader.fail(ManifestReader::join(path, "dtype"), fmt::format("'{}'", npyDescr<T>()), entry["dtype"]);
  const json& shapeJson = reader.member(entry, path, "shape");
  std::vector<std::size_t> shape;
  if (!shapeJson.is_array()) reader.fail(ManifestReader::join(path, "shape"), "an array of dimensions", shapeJson);
  for (const json& d : shapeJson) {
    if (!d.is_number_unsigned()) reader.fail(ManifestReader::join(path, "shape"), "non-negative integers", shapeJson);
    shape.push_back(d.get<std::size_t>());
  }
  const std::uint64_t bytes =
      reader.unsignedInteger(entry, path, "bytes", std::numeric_limits<std::uint64_t>::max());
  const std::string hash = reader.string(entry, path, "hash");

  const fs::path filePath = dir / file;
  const std::string source = filePath.string();
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(filePath, ec);
  if (ec)
    throw Error(fmt::format("{}: expected the file listed in manifest.json, found none ({})", source, ec.message()));
  // Before reading, so a huge stray file is refused without loading it.
  if (size != bytes)
    throw Error(fmt::format("{}: expected {} bytes as in manifest.json, found {}", source, bytes, size));
  const std::string text = readFile(filePath);
  if (text.size() != bytes)
    throw Error(fmt::format("{}: expected {} bytes as in manifest.json, found {}", source, bytes, text.size()));
  const std::string actualHash = hexDigest(hashBytes(text));
  if (actualHash != hash)
    throw Error(fmt::format("{}: expected hash {} as in manifest.json, found {} (the file was altered)", source,
                            quoteToken(hash), quoteToken(actualHash)));
  std::vector<std::size_t> fileShape;
  std::vector<T> data = npyDecode<T>(text, source, &fileShape);
  if (fileShape != shape)
    throw Error(fmt::format("{}: expected shape {} as in manifest.json, found {}", source, shapeText(shape),
                            shapeText(fileShape)));
  const bool shapeFits = columns == 1 ? fileShape.size() == 1 : fileShape.size() == 2 && fileShape[1] == columns;
  if (!shapeFits)
    throw Error(fmt::format("{}: expected shape {}, found {}", source,
                            columns == 1 ? std::string("(N,)") : fmt::format("(N, {})", columns),
                            shapeText(fileShape)));
  return data;
}

GraphBundleLoad damaged(std::string reason) {
  GraphBundleLoad result;
  result.status = GraphBundleLoad::Damaged;
  result.reason = std::move(reason);
  return result;
}

}  // namespace

void saveGraphBundle(const std::filesystem::path& dirArgument, const StateActionModel& m, const json& provenance) {
  // "cache/graph/" names the same bundle as "cache/graph".
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  const std::string source = dir.string();
  checkModel(m, source);
  if (!provenance.is_object() || !provenance.contains("key") || !provenance["key"].is_string())
    throw Error(fmt::format("{}: provenance: expected an object with a string \"key\", found {}", source,
                            quoteToken(provenance.dump(-1, ' ', false, json::error_handler_t::replace))));

  // Everything is encoded before touching the disk, so most failures leave nothing behind.
  std::vector<ArrayFile> files;
  json arrays = json::object();
  auto encode = [&](std::string_view name, const auto& values, std::size_t columns) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    const std::vector<std::size_t> shape = shapeOf(values.size(), columns);
    ArrayFile file{std::string(name), npyEncode<T>(values, shape)};
    arrays[file.name] = {{"file", fmt::format("{}.npy", name)},
                         {"dtype", std::string(npyDescr<T>())},
                         {"shape", shape},
                         {"bytes", file.bytes.size()},
                         {"hash", hexDigest(hashBytes(file.bytes))}};
    files.push_back(std::move(file));
  };
  forEachArray(m, encode);
  std::vector<std::uint32_t> hitsIndex;
  std::vector<float> hitsValue;
  for (const ActionHit& hit : m.hits) {
    hitsIndex.insert(hitsIndex.end(), {hit.action, hit.offset, hit.hand});
    hitsValue.insert(hitsValue.end(), {hit.x, hit.y, hit.z, hit.weight});
  }
  encode("hits_index", hitsIndex, kHitIndexColumns);
  encode("hits_value", hitsValue, kHitValueColumns);

  json manifest = {
      {"format", std::string(kGraphFormatName)},
      {"version", kGraphFormatVersion},
      {"provenance", provenance},
      {"scalars",
       {{"frame_time", m.frameTime},
        {"frames_total", m.framesTotal},
        {"centroid", {m.centroid[0], m.centroid[1], m.centroid[2]}},
        {"max_hit_speed_mps", m.maxHitSpeed_mps}}},
      {"arrays", std::move(arrays)},
  };
  std::string manifestText;
  try {
    manifestText = manifest.dump(2) + "\n";
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: provenance: expected valid UTF-8 strings, found {}", source, e.what()));
  }

  // Never delete something that is not ours to replace.
  std::error_code ec;
  const fs::file_status existing = fs::symlink_status(dir, ec);
  const bool replacing = fs::exists(existing);
  if (replacing) {
    if (!fs::is_directory(existing))
      throw Error(fmt::format("{}: expected a graph bundle directory or nothing, found another kind of file", source));
    if (!fs::exists(dir / "manifest.json", ec) && !fs::is_empty(dir, ec))
      throw Error(fmt::format("{}: expected a graph bundle (with manifest.json) or an empty directory to replace, "
                              "found a directory with other files; not deleting it",
                              source));
  }
  if (dir.has_parent_path()) {
    fs::create_directories(dir.parent_path(), ec);
    if (ec) throw Error(fmt::format("{}: cannot create {}: {}", source, dir.parent_path().string(), ec.message()));
  }

  const fs::path temporary = freshSibling(dir, "tmp", true);
  try {
    for (const ArrayFile& file : files) writeWholeFile(temporary / fmt::format("{}.npy", file.name), file.bytes);
    // Last, so a directory with a manifest has all its arrays.
    writeWholeFile(temporary / "manifest.json", manifestText);
    if (!replacing) {
      renameOrThrow(temporary, dir, source);
      return;
    }
    const fs::path old = freshSibling(dir, "old", false);
    renameOrThrow(dir, old, source);
    try {
      renameOrThrow(temporary, dir, source);
    } catch (const Error&) {
      std::error_code ignored;
      fs::rename(old, dir, ignored);  // put the previous bundle back
      throw;
    }
    // The new bundle is in place; an old copy that cannot be removed only wastes space.
    std::error_code ignored;
    fs::remove_all(old, ignored);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(temporary, ignored);
    throw;
  }
}

GraphBundleLoad loadGraphBundle(const std::filesystem::path& dirArgument, std::string_view expectedKey) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (status.type() == fs::file_type::not_found) {
    GraphBundleLoad result;
    result.status = GraphBundleLoad::Missing;
    result.reason = fmt::format("{}: no graph bundle there", dir.string());
    return result;
  }
  if (ec) return damaged(fmt::format("{}: cannot read: {}", dir.string(), ec.message()));
  if (!fs::is_directory(status))
    return damaged(fmt::format("{}: expected a graph bundle directory, found another kind of file", dir.string()));

  const fs::path manifestPath = dir / "manifest.json";
  const ManifestReader reader(manifestPath.string());
  try {
    json manifest;
    try {
      manifest = json::parse(readFile(manifestPath));
    } catch (const json::parse_error& e) {
      return damaged(fmt::format("{}: expected JSON, found a syntax error ({})", reader.source(), e.what()));
    }
    if (!manifest.is_object()) reader.fail("manifest", "a JSON object", manifest);

    const std::string format = reader.string(manifest, "", "format");
    const json& version = reader.member(manifest, "", "version");
    if (format != kGraphFormatName || version != kGraphFormatVersion) {
      GraphBundleLoad result;
      result.status = GraphBundleLoad::Stale;
      result.reason = fmt::format("{}: expected format '{}' version {}, found format {} version {}", reader.source(),
                                  kGraphFormatName, kGraphFormatVersion, quoteToken(format),
                                  quoteToken(version.dump(-1, ' ', false, json::error_handler_t::replace)));
      result.manifest = std::move(manifest);
      return result;
    }
    reader.object(manifest, "", "provenance", {});
    const std::string key = reader.string(manifest["provenance"], "provenance", "key");
    if (key != expectedKey) {
      GraphBundleLoad result;
      result.status = GraphBundleLoad::Stale;
      result.reason = fmt::format("{}: expected cache key {}, found {} (built from other inputs)", reader.source(),
                                  quoteToken(expectedKey), quoteToken(key));
      result.manifest = std::move(manifest);
      return result;
    }
    for (const auto& item : manifest.items())
      if (item.key() != "format" && item.key() != "version" && item.key() != "provenance" && item.key() != "scalars" &&
          item.key() != "arrays")
        throw Error(fmt::format("{}: expected only the keys format, version, provenance, scalars, arrays, found '{}'",
                                reader.source(), item.key()));

    GraphBundleLoad result;
    StateActionModel& m = result.model;
    const json& scalars =
        reader.object(manifest, "", "scalars", {"frame_time", "frames_total", "centroid", "max_hit_speed_mps"});
    m.frameTime = reader.number(scalars, "scalars", "frame_time");
    m.framesTotal = static_cast<std::uint32_t>(
        reader.unsignedInteger(scalars, "scalars", "frames_total", std::numeric_limits<std::uint32_t>::max()));
    const json& centroid = reader.member(scalars, "scalars", "centroid");
    if (!centroid.is_array() || centroid.size() != 3 ||
        !std::all_of(centroid.begin(), centroid.end(), [](const json& v) { return v.is_number(); }))
      reader.fail("scalars.centroid", "3 numbers", centroid);
    for (int i = 0; i < 3; ++i) m.centroid[i] = centroid[i].get<double>();
    m.maxHitSpeed_mps = reader.number(scalars, "scalars", "max_hit_speed_mps");

    const json& arrays = reader.object(manifest, "", "arrays", {});
    std::set<std::string, std::less<>> known;
    auto load = [&](std::string_view name, auto& values, std::size_t columns) {
      using T = typename std::decay_t<decltype(values)>::value_type;
      values = loadArray<T>(dir, reader, arrays, name, columns);
      known.emplace(name);
    };
    forEachArray(m, load);
    std::vector<std::uint32_t> hitsIndex;
    std::vector<float> hitsValue;
    load("hits_index", hitsIndex, kHitIndexColumns);
    load("hits_value", hitsValue, kHitValueColumns);
    for (const auto& item : arrays.items())
      if (!known.contains(item.key()))
        throw Error(fmt::format("{}: arrays: expected only the arrays of a state-action model, found '{}'",
                                reader.source(), item.key()));

    const std::size_t hitCount = hitsIndex.size() / kHitIndexColumns;
    if (hitsValue.size() != hitCount * kHitValueColumns)
      throw Error(fmt::format("{}: expected {} rows, as hits_index.npy has, found {}",
                              (dir / "hits_value.npy").string(), hitCount, hitsValue.size() / kHitValueColumns));
    m.hits.resize(hitCount);
    for (std::size_t h = 0; h < hitCount; ++h) {
      const std::uint32_t* index = &hitsIndex[kHitIndexColumns * h];
      const float* value = &hitsValue[kHitValueColumns * h];
      // Checked here because narrowing to uint8 would hide a bad hand (257 -> 1).
      if (index[2] > 1)
        throw Error(fmt::format("{}: hit {}: expected hand 0 or 1, found {}", (dir / "hits_index.npy").string(), h,
                                index[2]));
      m.hits[h] = ActionHit{index[0], index[1], static_cast<std::uint8_t>(index[2]),
                            value[0], value[1], value[2], value[3]};
    }

    checkModel(m, dir.string());
    result.status = GraphBundleLoad::Ok;
    result.manifest = std::move(manifest);
    return result;
  } catch (const Error& e) {
    return damaged(e.what());
  } catch (const json::exception& e) {
    return damaged(fmt::format("{}: {}", reader.source(), e.what()));
  } catch (const fs::filesystem_error& e) {
    return damaged(e.what());
  }
}

}  // namespace mgrl
