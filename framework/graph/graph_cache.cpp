#include "mgrl/graph/graph_cache.hpp"

#include <algorithm>
#include <cmath>
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
  visit("role_joint", m.roleJoint, 1);
  visit("source_joint", m.sourceJoint, 3);
  visit("source_joint_speed", m.sourceJointSpeed, 1);
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

// ---------------------------------------------------------------------------------------
// The capture's motions (version 4, "motion")

json vectorJson(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json jointJson(const Joint& joint) {
  json channels = json::array();
  for (const Channel& c : joint.channels) channels.push_back(channelName(c));
  json j = {{"name", joint.name}, {"parent", joint.parent}, {"offset", vectorJson(joint.offset)}, {"channels", channels}};
  if (joint.endSite) j["end_site"] = vectorJson(*joint.endSite);
  return j;
}

// The "motion" member and the two arrays' values, in the order of the file comment.
json motionJson(std::span<const Clip> clips, std::vector<double>& rotations, std::vector<double>& translations) {
  json list = json::array();
  for (const Clip& clip : clips) {
    const Motion& motion = clip.motion;
    json joints = json::array();
    for (const Joint& joint : motion.skeleton().joints()) joints.push_back(jointJson(joint));
    list.push_back({{"name", clip.name},
                    {"frames", motion.frameCount()},
                    {"frame_time", motion.frameTime()},
                    {"joints", std::move(joints)}});
    for (std::size_t f = 0; f < motion.frameCount(); ++f) {
      for (const Eigen::Quaterniond& q : motion.rotations(f)) rotations.insert(rotations.end(), {q.x(), q.y(), q.z(), q.w()});
      for (const Eigen::Vector3d& t : motion.translations(f)) translations.insert(translations.end(), {t.x(), t.y(), t.z()});
    }
  }
  return {{"clips", std::move(list)}};
}

Eigen::Vector3d readVector(const ManifestReader& reader, const json& parent, const std::string& path,
                           std::string_view key) {
  const json& v = reader.member(parent, path, key);
  if (!v.is_array() || v.size() != 3 ||
      !std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number() && std::isfinite(x.get<double>()); }))
    reader.fail(ManifestReader::join(path, key), "3 finite numbers", v);
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

Joint readJoint(const ManifestReader& reader, const json& j, const std::string& path) {
  if (!j.is_object()) reader.fail(path, "an object", j);
  for (const auto& item : j.items())
    if (item.key() != "name" && item.key() != "parent" && item.key() != "offset" && item.key() != "channels" &&
        item.key() != "end_site")
      reader.fail(path, "only the keys name, parent, offset, channels, end_site", json(item.key()));
  Joint joint;
  joint.name = reader.string(j, path, "name");
  const json& parent = reader.member(j, path, "parent");
  if (!parent.is_number_integer() || parent.get<std::int64_t>() < -1 ||
      parent.get<std::int64_t>() >= static_cast<std::int64_t>(kMaxBundledJoints))
    reader.fail(ManifestReader::join(path, "parent"), fmt::format("an integer in [-1, {})", kMaxBundledJoints), parent);
  joint.parent = static_cast<int>(parent.get<std::int64_t>());
  joint.offset = readVector(reader, j, path, "offset");
  const json& channels = reader.member(j, path, "channels");
  if (!channels.is_array() || channels.size() > 6)
    reader.fail(ManifestReader::join(path, "channels"), "an array of at most 6 channel names", channels);
  for (const json& c : channels) {
    const std::optional<Channel> channel = c.is_string() ? channelFromName(c.get<std::string>()) : std::nullopt;
    if (!channel)
      reader.fail(ManifestReader::join(path, "channels"), "channel names such as 'Zrotation' or 'Xposition'", c);
    joint.channels.push_back(*channel);
  }
  if (j.contains("end_site")) joint.endSite = readVector(reader, j, path, "end_site");
  return joint;
}

// The clips of a version 4 bundle. Sizes are checked against each other and the model
// before the arrays are read, and the arrays against the sizes before a motion is built.
std::vector<std::pair<std::string, Motion>> loadMotions(const fs::path& dir, const ManifestReader& reader,
                                                        const json& manifest, const json& arrays,
                                                        const StateActionModel& m) {
  struct ClipHeader {
    std::string name;
    std::size_t frames = 0;
    double frameTime = 0;
    std::shared_ptr<const Skeleton> skeleton;
  };
  const json& motion = reader.object(manifest, "", "motion", {"clips"});
  const json& clips = reader.member(motion, "motion", "clips");
  if (!clips.is_array() || clips.empty() || clips.size() > kMaxBundledClips)
    reader.fail("motion.clips", fmt::format("an array of 1 to {} clips", kMaxBundledClips), clips);
  if (m.clipOffset.size() != clips.size() + 1)
    throw Error(fmt::format("{}: motion.clips: expected {} clips as clip_offset.npy says, found {}", reader.source(),
                            m.clipOffset.size() - 1, clips.size()));
  std::vector<ClipHeader> headers;
  std::uint64_t rotationRows = 0, translationRows = 0;
  for (std::size_t c = 0; c < clips.size(); ++c) {
    const std::string path = fmt::format("motion.clips[{}]", c);
    const json& clip = clips[c];
    if (!clip.is_object()) reader.fail(path, "an object", clip);
    for (const auto& item : clip.items())
      if (item.key() != "name" && item.key() != "frames" && item.key() != "frame_time" && item.key() != "joints")
        reader.fail(path, "only the keys name, frames, frame_time, joints", json(item.key()));
    ClipHeader h;
    h.name = reader.string(clip, path, "name");
    h.frames = reader.unsignedInteger(clip, path, "frames", kMaxResampledFrames);
    if (h.frames != m.clipOffset[c + 1] - m.clipOffset[c])
      reader.fail(ManifestReader::join(path, "frames"),
                  fmt::format("{} as clip_offset.npy says", m.clipOffset[c + 1] - m.clipOffset[c]), clip["frames"]);
    h.frameTime = reader.number(clip, path, "frame_time");
    if (h.frameTime != m.frameTime) reader.fail(ManifestReader::join(path, "frame_time"), "scalars.frame_time", clip["frame_time"]);
    const json& joints = reader.member(clip, path, "joints");
    const std::string expectedJoints = fmt::format("an array of 1 to {} joints", kMaxBundledJoints);
    if (!joints.is_array()) reader.fail(ManifestReader::join(path, "joints"), expectedJoints, joints);
    if (joints.empty() || joints.size() > kMaxBundledJoints)
      throw Error(fmt::format("{}: {}.joints: expected {}, found {}", reader.source(), path, expectedJoints,
                              joints.size()));
    std::vector<Joint> list;
    for (std::size_t j = 0; j < joints.size(); ++j)
      list.push_back(readJoint(reader, joints[j], fmt::format("{}.joints[{}]", path, j)));
    try {
      h.skeleton = std::make_shared<const Skeleton>(std::move(list));
    } catch (const Error& e) {
      throw Error(fmt::format("{}: {}.joints: {}", reader.source(), path, e.what()));
    }
    rotationRows += std::uint64_t{h.frames} * h.skeleton->jointCount();
    translationRows += std::uint64_t{h.frames} * h.skeleton->translatedJoints().size();
    headers.push_back(std::move(h));
  }

  const MappedBundleArray<double> rotations =
      mapBundleArray<double>(dir, reader, arrays, "arrays", "motion_rotations", "motion_rotations.npy");
  const MappedBundleArray<double> translations =
      mapBundleArray<double>(dir, reader, arrays, "arrays", "motion_translations", "motion_translations.npy");
  auto requireShape = [&](const MappedBundleArray<double>& a, std::string_view name, std::uint64_t rows,
                          std::size_t columns) {
    if (a.shape != std::vector<std::size_t>{rows, columns})
      throw Error(fmt::format("{}: expected shape ({}, {}) as motion.clips says, found {}",
                              (dir / fmt::format("{}.npy", name)).string(), rows, columns, formatShape(a.shape)));
  };
  requireShape(rotations, "motion_rotations", rotationRows, 4);
  requireShape(translations, "motion_translations", translationRows, 3);

  std::vector<std::pair<std::string, Motion>> motions;
  motions.reserve(headers.size());
  const double* r = rotations.data.data();
  const double* t = translations.data.data();
  for (ClipHeader& h : headers) {
    std::vector<Eigen::Quaterniond> q(h.frames * h.skeleton->jointCount());
    for (Eigen::Quaterniond& x : q) {
      x = Eigen::Quaterniond(r[3], r[0], r[1], r[2]);
      // The hash vouches for the bytes, not that a writer put rotations there.
      if (!(std::abs(x.squaredNorm() - 1) < 1e-6))
        throw Error(fmt::format("{}: row {}: expected a unit quaternion, found ({}, {}, {}, {})",
                                (dir / "motion_rotations.npy").string(), (r - rotations.data.data()) / 4, r[0], r[1],
                                r[2], r[3]));
      r += 4;
    }
    std::vector<Eigen::Vector3d> v(h.frames * h.skeleton->translatedJoints().size());
    for (Eigen::Vector3d& x : v) {
      x = Eigen::Vector3d(t[0], t[1], t[2]);
      if (!x.allFinite())
        throw Error(fmt::format("{}: row {}: expected finite numbers, found ({}, {}, {})",
                                (dir / "motion_translations.npy").string(), (t - translations.data.data()) / 3, t[0],
                                t[1], t[2]));
      t += 3;
    }
    motions.emplace_back(std::move(h.name), Motion(h.skeleton, h.frameTime, std::move(q), std::move(v)));
  }
  return motions;
}

GraphBundleLoad damaged(std::string reason) {
  GraphBundleLoad result;
  result.status = GraphBundleLoad::Damaged;
  result.reason = std::move(reason);
  return result;
}

}  // namespace

void saveGraphBundle(const std::filesystem::path& dirArgument, const StateActionModel& m, const json& provenance,
                     std::span<const Clip> clips) {
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
  json motion;
  if (!clips.empty()) {
    std::size_t frames = 0;
    for (const Clip& clip : clips) frames += clip.motion.frameCount();
    if (clips.size() + 1 != m.clipOffset.size() || frames != m.framesTotal)
      throw Error(fmt::format("{}: expected the {} clips of {} frames the model was built from, found {} of {}", source,
                              m.clipOffset.size() - 1, m.framesTotal, clips.size(), frames));
    std::vector<double> rotations, translations;
    motion = motionJson(clips, rotations, translations);
    encode("motion_rotations", rotations, 4);
    encode("motion_translations", translations, 3);
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
        {"max_kick_speed_mps", m.maxKickSpeed_mps},
        {"joint_names", m.jointNames}}},
      {"arrays", std::move(arrays)},
  };
  if (!motion.is_null()) manifest["motion"] = std::move(motion);
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

GraphBundleLoad loadGraphBundle(const std::filesystem::path& dirArgument, std::string_view expectedKey,
                                bool withMotion) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  recoverBundleDirectory(dir, "manifest.json");  // what a killed writer left
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
          item.key() != "arrays" && item.key() != "hash" && item.key() != "motion")
        throw Error(fmt::format("{}: expected only the keys format, version, provenance, scalars, arrays, motion, hash, "
                                "found '{}'",
                                reader.source(), item.key()));

    GraphBundleLoad result;
    StateActionModel& m = result.model;
    const json& scalars =
        reader.object(manifest, "", "scalars",
                      {"frame_time", "frames_total", "centroid", "max_hit_speed_mps", "max_kick_speed_mps",
                       "joint_names"});
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
    const json& jointNames = reader.member(scalars, "scalars", "joint_names");
    if (!jointNames.is_array() || jointNames.size() > kMaxBundledJoints ||
        !std::all_of(jointNames.begin(), jointNames.end(), [](const json& v) { return v.is_string(); }))
      reader.fail("scalars.joint_names", fmt::format("an array of at most {} joint names", kMaxBundledJoints),
                  jointNames);
    for (const json& name : jointNames) {
      const std::string& text = name.get_ref<const std::string&>();
      // Names reach messages (a body point the skeleton lacks lists them): printable, bounded.
      if (text.empty() || text.size() > 200 ||
          !std::all_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) >= ' ' && c != 0x7f; }))
        reader.fail("scalars.joint_names", "joint names of 1 to 200 printable characters", name);
      m.jointNames.push_back(text);
    }

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
    const bool hasMotion = manifest.contains("motion");
    if (hasMotion) known.insert({"motion_rotations", "motion_translations"});
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
    if (withMotion && hasMotion) result.motions = loadMotions(dir, reader, manifest, arrays, m);
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
