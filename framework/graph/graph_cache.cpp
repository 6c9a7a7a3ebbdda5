#include "mgrl/graph/graph_cache.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <set>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/npy.hpp"

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
  visit("action_kick_begin", m.actionKickBegin, 1);
}

constexpr std::size_t kHitIndexColumns = 3;  // action, offset, hand
constexpr std::size_t kHitValueColumns = 4;  // x, y, z, weight

std::vector<std::size_t> shapeOf(std::size_t size, std::size_t columns) {
  if (columns == 1) return {size};
  return {size / columns, columns};
}

// ---------------------------------------------------------------------------------------
// Loading

// One array: the generic checks against its manifest entry, then the columns the model needs.
template <NpyElement T>
std::vector<T> loadArray(const fs::path& dir, const ManifestReader& reader, const json& arrays,
                         std::string_view name, std::size_t columns) {
  std::vector<std::size_t> shape;
  std::vector<T> data = loadBundleArray<T>(dir, reader, arrays, "arrays", name, fmt::format("{}.npy", name), &shape);
  const bool shapeFits = columns == 1 ? shape.size() == 1 : shape.size() == 2 && shape[1] == columns;
  if (!shapeFits)
    throw Error(fmt::format("{}: expected shape {}, found {}", (dir / fmt::format("{}.npy", name)).string(),
                            columns == 1 ? std::string("(N,)") : fmt::format("(N, {})", columns),
                            formatShape(shape)));
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
  std::vector<BundleFile> files;
  json arrays = json::object();
  auto encode = [&](std::string_view name, const auto& values, std::size_t columns) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    EncodedArray array =
        encodeBundleArray<T>(fmt::format("{}.npy", name), values, shapeOf(values.size(), columns));
    arrays[std::string(name)] = std::move(array.entry);
    files.push_back(std::move(array.file));
  };
  forEachArray(m, encode);
  for (const auto& [name, list] : {std::pair{"hits", &m.hits}, std::pair{"kicks", &m.kicks}}) {
    std::vector<std::uint32_t> index;
    std::vector<float> value;
    for (const ActionHit& hit : *list) {
      index.insert(index.end(), {hit.action, hit.offset, hit.hand});
      value.insert(value.end(), {hit.x, hit.y, hit.z, hit.weight});
    }
    encode(fmt::format("{}_index", name), index, kHitIndexColumns);
    encode(fmt::format("{}_value", name), value, kHitValueColumns);
  }

  json manifest = {
      {"format", std::string(kGraphFormatName)},
      {"version", kGraphFormatVersion},
      {"provenance", provenance},
      {"scalars",
       {{"frame_time", m.frameTime},
        {"frames_total", m.framesTotal},
        {"centroid", {m.centroid[0], m.centroid[1], m.centroid[2]}},
        {"max_hit_speed_mps", m.maxHitSpeed_mps},
        {"max_kick_speed_mps", m.maxKickSpeed_mps}}},
      {"arrays", std::move(arrays)},
  };
  std::string manifestText;
  try {
    // The scalars are the model's too: sealed like the arrays, so a flipped bit is noticed.
    manifest["hash"] = manifestHash(manifest);
    manifestText = manifest.dump(2) + "\n";
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: provenance: expected valid UTF-8 strings, found {}", source, e.what()));
  }

  writeBundleDirectory(dir, files, manifestText, "graph bundle");
}

GraphBundleLoad loadGraphBundle(const std::filesystem::path& dirArgument, std::string_view expectedKey) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  recoverBundleDirectory(dir, "manifest.json");  // what a killed writer left (issue 19)
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
    json manifest = readManifestObject(manifestPath);

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
    // Before anything else is read from it: every value below is then as saved.
    checkManifestHash(manifest, reader);
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
          item.key() != "arrays" && item.key() != "hash")
        throw Error(fmt::format("{}: expected only the keys format, version, provenance, scalars, arrays, hash, found '{}'",
                                reader.source(), item.key()));

    GraphBundleLoad result;
    StateActionModel& m = result.model;
    const json& scalars =
        reader.object(manifest, "", "scalars",
                      {"frame_time", "frames_total", "centroid", "max_hit_speed_mps", "max_kick_speed_mps"});
    m.frameTime = reader.number(scalars, "scalars", "frame_time");
    m.framesTotal = static_cast<std::uint32_t>(
        reader.unsignedInteger(scalars, "scalars", "frames_total", std::numeric_limits<std::uint32_t>::max()));
    const json& centroid = reader.member(scalars, "scalars", "centroid");
    if (!centroid.is_array() || centroid.size() != 3 ||
        !std::all_of(centroid.begin(), centroid.end(), [](const json& v) { return v.is_number(); }))
      reader.fail("scalars.centroid", "3 numbers", centroid);
    for (int i = 0; i < 3; ++i) m.centroid[i] = centroid[i].get<double>();
    m.maxHitSpeed_mps = reader.number(scalars, "scalars", "max_hit_speed_mps");
    m.maxKickSpeed_mps = reader.number(scalars, "scalars", "max_kick_speed_mps");

    const json& arrays = reader.object(manifest, "", "arrays", {});
    std::set<std::string, std::less<>> known;
    auto load = [&](std::string_view name, auto& values, std::size_t columns) {
      using T = typename std::decay_t<decltype(values)>::value_type;
      values = loadArray<T>(dir, reader, arrays, name, columns);
      known.emplace(name);
    };
    forEachArray(m, load);
    std::vector<std::uint32_t> hitsIndex, kicksIndex;
    std::vector<float> hitsValue, kicksValue;
    load("hits_index", hitsIndex, kHitIndexColumns);
    load("hits_value", hitsValue, kHitValueColumns);
    load("kicks_index", kicksIndex, kHitIndexColumns);
    load("kicks_value", kicksValue, kHitValueColumns);
    for (const auto& item : arrays.items())
      if (!known.contains(item.key()))
        throw Error(fmt::format("{}: arrays: expected only the arrays of a state-action model, found '{}'",
                                reader.source(), item.key()));

    // Strikes: effective punches (hits, hand 0/1) and kicks (foot 0/1), split in two arrays each.
    auto strikes = [&](std::string_view name, const std::vector<std::uint32_t>& indexes,
                       const std::vector<float>& values, std::vector<ActionHit>& out) {
      const std::size_t count = indexes.size() / kHitIndexColumns;
      if (values.size() != count * kHitValueColumns)
        throw Error(fmt::format("{}: expected {} rows, as {}_index.npy has, found {}",
                                (dir / fmt::format("{}_value.npy", name)).string(), count, name,
                                values.size() / kHitValueColumns));
      out.resize(count);
      for (std::size_t h = 0; h < count; ++h) {
        const std::uint32_t* index = &indexes[kHitIndexColumns * h];
        const float* value = &values[kHitValueColumns * h];
        // Checked here because narrowing to uint8 would hide a bad side (257 -> 1).
        if (index[2] > 1)
          throw Error(fmt::format("{}: row {}: expected side 0 or 1 in column 2, found {}",
                                  (dir / fmt::format("{}_index.npy", name)).string(), h, index[2]));
        out[h] = ActionHit{index[0], index[1], static_cast<std::uint8_t>(index[2]), value[0], value[1], value[2],
                           value[3]};
      }
    };
    strikes("hits", hitsIndex, hitsValue, m.hits);
    strikes("kicks", kicksIndex, kicksValue, m.kicks);

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
