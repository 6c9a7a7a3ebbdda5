#include "mgrl/session/exports.hpp"

#include <chrono>
#include <ctime>
#include <fstream>
#include <set>

#include <signal.h>
#include <unistd.h>

#include <cerrno>

#include <fmt/format.h>

#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/gltf.hpp"
#include "mgrl/motion/motion_io.hpp"

namespace mgrl {

namespace fs = std::filesystem;

using json = nlohmann::json;

namespace {

std::string scratchName() { return fmt::format(".mgrl-simulate-{}", ::getpid()); }

// The scratch folders of runs that were killed (their process is gone)
// are removed; a live run's are left alone.
void removeStaleScratch(const fs::path& dir) {
  std::error_code ec;
  constexpr std::string_view prefix = ".mgrl-simulate-";
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0 || name.size() == prefix.size() || name.size() > prefix.size() + 10 ||
        name.find_first_not_of("0123456789", prefix.size()) != std::string::npos)
      continue;
    const long pid = std::stol(name.substr(prefix.size()));
    if (pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM) continue;
    std::error_code ignored;
    fs::remove_all(it->path(), ignored);
  }
}

// Creates `dir` if needed and a scratch folder inside it; throws if either fails (and
// then leaves nothing created).
std::unique_ptr<ScratchDirectory> prepareFolder(const fs::path& dir, std::string_view flag) {
  std::error_code ec;
  // The outermost missing folder on the way to `dir`, to remove if the run fails.
  fs::path created;
  for (fs::path p = fs::absolute(dir, ec); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created = p;
    if (p == p.parent_path()) break;
  }
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    if (!created.empty()) fs::remove_all(created, ec);
    throw Error(fmt::format("{} {}: expected a folder that can be created, found: {}", flag, dir.string(),
                            ec ? ec.message() : std::string("not a folder")));
  }
  removeStaleScratch(dir);
  const fs::path scratch = dir / scratchName();
  fs::remove_all(scratch, ec);
  auto guard = std::make_unique<ScratchDirectory>(scratch, created);
  if (!fs::create_directory(scratch, ec) || ec)
    throw Error(fmt::format("{} {}: expected a writable folder, found: {}", flag, dir.string(),
                            ec ? ec.message() : std::string("cannot create files there")));
  std::ofstream probe(scratch / "probe");
  if (!(probe << "x") || !probe.flush())
    throw Error(
        fmt::format("{} {}: expected a writable folder, found one where files cannot be written", flag, dir.string()));
  probe.close();
  fs::remove(scratch / "probe", ec);
  return guard;
}

// --bvh-out's folder is one unit (a bundle, mgrl/core/bundle.hpp):
// written beside it and swapped in whole, with a manifest naming the run. Only simulate's
// own output is replaced: an empty folder, an earlier run's (its manifest and the files it
// lists), or what simulate wrote before folders had manifests (avatar_NNN.bvh, *.jsonl);
// besides killed runs' .mgrl-simulate-PID scratch folders. Anything else is the user's.
constexpr std::string_view kOutputFormat = "mgrl-simulate-output";
constexpr int kOutputVersion = 1;

bool earlierSimulateOutput(const fs::path& dir) {
  std::set<std::string> listed;
  std::error_code ec;
  const bool hasManifest = fs::is_regular_file(dir / "manifest.json", ec);
  if (hasManifest) {
    std::string text;
    try {
      text = readFile(dir / "manifest.json");
    } catch (const Error&) {
      return false;
    }
    const json manifest = json::parse(text, nullptr, false);
    if (!manifest.is_object() || manifest.value("format", "") != kOutputFormat || !manifest["files"].is_array())
      return false;
    listed.insert("manifest.json");
    for (const json& file : manifest["files"])
      if (file.is_object() && file["file"].is_string()) listed.insert(file["file"].get<std::string>());
  }
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(".mgrl-simulate-", 0) == 0 && it->is_directory(ec)) continue;
    if (!it->is_regular_file(ec)) return false;
    if (hasManifest) {
      if (!listed.count(name)) return false;
      continue;
    }
    const bool avatar = name.size() > 11 && name.rfind("avatar_", 0) == 0 && name.ends_with(".bvh") &&
                        name.find_first_not_of("0123456789", 7) == name.size() - 4;
    if (!avatar && !name.ends_with(".jsonl")) return false;
  }
  return !ec;
}

// Creates an output folder's parents and the bundle's temporary beside the folder; throws
// if either fails (and then leaves nothing created). `option` names it in messages.
std::unique_ptr<BundleWriter> prepareBundle(const fs::path& dirArgument, std::unique_ptr<ScratchDirectory>& created,
                                            std::string_view option) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (fs::exists(status) && !fs::is_directory(status))
    throw Error(fmt::format("{} {}: expected a folder, found another kind of file", option, dir.string()));
  // The outermost missing folder on the way to `dir`'s parent, to remove if the run fails.
  fs::path outermost;
  for (fs::path p = fs::absolute(dir, ec).parent_path(); !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    outermost = p;
    if (p == p.parent_path()) break;
  }
  if (dir.has_parent_path()) {
    fs::create_directories(dir.parent_path(), ec);
    if (ec || !fs::is_directory(dir.parent_path())) {
      if (!outermost.empty()) fs::remove_all(outermost, ec);
      throw Error(fmt::format("{} {}: expected a folder that can be created, found: {}", option, dir.string(),
                              ec ? ec.message() : std::string("not a folder")));
    }
  }
  created = std::make_unique<ScratchDirectory>(fs::path(), outermost);
  if (fs::is_directory(dir)) removeStaleScratch(dir);
  try {
    return std::make_unique<BundleWriter>(dir, "simulate output", "manifest.json", earlierSimulateOutput);
  } catch (const Error& e) {
    throw Error(fmt::format("{} {}", option, e.what()));
  }
}

std::string utcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  ::gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string eventLine(const HitEvent& e) { return hitEventJson(e).dump(); }

// A folder argument as an absolute, normal path without a trailing separator.
fs::path folderOf(const fs::path& p) {
  fs::path absolute = fs::absolute(p).lexically_normal();
  return absolute.has_filename() ? absolute : absolute.parent_path();
}

// avatar_NNN.bvh or avatar_NNN.glb: the name of a file an output folder holds per avatar.
bool avatarFileName(std::string_view name) {
  return name.rfind("avatar_", 0) == 0 && (name.ends_with(".bvh") || name.ends_with(".glb"));
}

// The look of an exported body: gloves on the fists (and what hangs under them) and the
// wrists, shoes on the ankles and toes, the rest of the body in the avatar's colour
// (sparring partners differ); the trunk (pelvis up to the neck) wider than the limbs, the
// head a ball, the fists glove-sized.
GltfWriteOptions gltfOptions(const Skeleton& skeleton, const SkeletonRoles& roles, std::size_t avatar,
                             const std::string& name) {
  GltfWriteOptions options;
  options.name = name;
  options.bodyColor = avatar % 2 == 0 ? Eigen::Vector3f(0.20f, 0.36f, 0.70f) : Eigen::Vector3f(0.72f, 0.42f, 0.16f);
  const Eigen::Vector3f glove(0.75f, 0.08f, 0.08f), shoe(0.12f, 0.12f, 0.12f);
  std::vector<char> gloved(skeleton.jointCount(), 0);
  for (int side = 0; side < 2; ++side) {
    if (roles.fist[side] >= 0) gloved[static_cast<std::size_t>(roles.fist[side])] = 1;
    if (roles.wrist[side] >= 0) options.jointColors[roles.wrist[side]] = glove;
    if (roles.ankle[side] >= 0) options.jointColors[roles.ankle[side]] = shoe;
    if (roles.toe[side] >= 0) options.jointColors[roles.toe[side]] = shoe;
  }
  for (std::size_t j = 1; j < skeleton.jointCount(); ++j)  // parents come first
    if (gloved[static_cast<std::size_t>(skeleton.joint(j).parent)]) gloved[j] = 1;
  for (std::size_t j = 0; j < skeleton.jointCount(); ++j)
    if (gloved[j]) options.jointColors[static_cast<int>(j)] = glove;
  // The trunk: the head's ancestors down to the pelvis (the neck's bones narrower).
  if (roles.head >= 0 && roles.pelvis >= 0) {
    std::vector<int> chain;
    for (int j = skeleton.joint(static_cast<std::size_t>(roles.head)).parent; j >= 0 && j != roles.pelvis;
         j = skeleton.joint(static_cast<std::size_t>(j)).parent)
      chain.push_back(j);
    const std::size_t neck = std::min<std::size_t>(chain.size(), 2);  // the two joints under the head
    for (std::size_t k = 0; k < chain.size(); ++k) options.jointRadii[chain[k]] = k < neck ? 0.05 : 0.1;
    options.jointRadii[roles.pelvis] = 0.1;
    options.jointRadii[roles.head] = 0.1;
  }
  for (int side = 0; side < 2; ++side)
    if (roles.fist[side] >= 0) options.jointRadii[roles.fist[side]] = 0.05;
  return options;
}

}  // namespace

double recordingBytes(double avatarFrames, double joints) {
  return avatarFrames * (joints * (sizeof(Eigen::Quaterniond) + sizeof(Eigen::Vector3d)) + 64);
}

Outputs prepareOutputs(const ExportRequest& options, const Scenario& scenario) {
  Outputs out;
  if (!options.bvhOut.empty()) {
    OutputFolder& folder = out.folders.emplace_back();
    folder.option = options.fields.bvhOut;
    folder.dir = options.bvhOut;
    folder.bvh = true;
  }
  if (!options.gltfOut.empty()) {
    if (!out.folders.empty() && folderOf(options.gltfOut) == folderOf(options.bvhOut)) {
      out.folders.front().gltf = true;  // one folder, one unit, both formats
      out.folders.front().option = fmt::format("{} and {}", options.fields.bvhOut, options.fields.gltfOut);
    } else {
      OutputFolder& folder = out.folders.emplace_back();
      folder.option = options.fields.gltfOut;
      folder.dir = options.gltfOut;
      folder.gltf = true;
    }
  }
  // An events file directly inside an output folder is one of that folder's files, so it
  // is replaced with the motion files as one unit.
  OutputFolder* eventsFolder = nullptr;
  for (OutputFolder& folder : out.folders)
    if (!options.eventsOut.empty() && folderOf(options.eventsOut).parent_path() == folderOf(folder.dir)) {
      folder.events = true;
      eventsFolder = &folder;
    }
  // Output places are checked (and scratch folders made) before any simulation: first
  // what can be checked without creating anything.
  if (!options.eventsOut.empty()) {
    if (fs::is_directory(options.eventsOut))
      throw Error(fmt::format("{} {}: expected a file name, found a folder", options.fields.eventsOut,
                              options.eventsOut.string()));
    // A missing folder is made, as for --bvh-out (prepareFolder and prepareBundle below).
  }
  if (!out.folders.empty()) {
    // A first estimate with a small skeleton (20 joints), exact once the skeleton is known.
    const double avatarFrames =
        static_cast<double>(options.avatars) * std::round(options.seconds * scenario.motion.fps);
    if (recordingBytes(avatarFrames, 20) > kMaxRecordingBytes)
      throw Error(fmt::format(
          "{}: recording {} avatars for {} s needs more than {:.1f} GB of memory; expected "
          "at most {:.0f} GB: use fewer {} or {}",
          out.folders.front().option, options.avatars, options.seconds, recordingBytes(avatarFrames, 20) / 1e9,
          kMaxRecordingBytes / 1e9, options.fields.avatars, options.fields.seconds));
  }
  if (eventsFolder) {
    const std::string name = options.eventsOut.filename().string();
    if (name == "manifest.json" || avatarFileName(name))
      throw Error(
          fmt::format("{} {}: expected a name other than the {} folder's own files "
                      "(manifest.json, avatar_NNN.bvh, avatar_NNN.glb), found {}",
                      options.fields.eventsOut, options.eventsOut.string(), eventsFolder->option, quoteToken(name)));
  }
  if (!options.eventsOut.empty() && !eventsFolder) {
    const fs::path parent = options.eventsOut.parent_path().empty() ? fs::path(".") : options.eventsOut.parent_path();
    out.eventsScratch = prepareFolder(parent, options.fields.eventsOut);
  }
  for (OutputFolder& folder : out.folders) folder.bundle = prepareBundle(folder.dir, folder.created, folder.option);
  return out;
}

WrittenFiles writeOutputs(Outputs& out, const ExportRequest& options, const Session& session, const World& world,
                          std::size_t frames) {
  const StateActionModel& model = session.model();
  const std::size_t avatars = world.avatarCount();
  const Scenario& scenario = session.scenario;
  const GraphResult& graph = session.graph;
  const WorldParams& params = world.params();
  const fs::path& policyDir = session.policyDir;
  std::string eventsText;
  for (const HitEvent& e : world.events()) eventsText += eventLine(e) + '\n';
  fs::path eventsTemporary;
  if (out.eventsScratch) {
    eventsTemporary = out.eventsScratch->path() / "events.jsonl";
    writeWholeFile(eventsTemporary, eventsText);
  }
  WrittenFiles written;
  const int width = std::max(static_cast<int>(std::to_string(avatars - 1).size()), 3);
  for (OutputFolder& folder : out.folders) {
    json files = json::array();
    auto add = [&](const std::string& name, const std::string& bytes) {
      writeWholeFile(folder.bundle->path() / name, bytes);
      files.push_back({{"file", name}, {"bytes", bytes.size()}, {"hash", hexDigest(hashBytes(bytes))}});
    };
    for (std::size_t i = 0; i < avatars; ++i) {
      const Motion motion = motionFromPoses(graph.db.skeleton, world.recorded(i), model.frameTime);
      const std::string stem = fmt::format("avatar_{:0{}}", i, width);
      if (folder.bvh) {
        BvhWriteOptions bvhOptions;
        bvhOptions.lengthScale = 100;  // centimetres, as most tools expect
        bvhOptions.continuousAngles = true;
        std::ostringstream text;
        writeBvh(text, motion, bvhOptions);
        add(stem + ".bvh", std::move(text).str());
        written.bvh.push_back((folder.dir / (stem + ".bvh")).string());
      }
      if (folder.gltf) {
        add(stem + ".glb", writeGlb(motion, gltfOptions(*graph.db.skeleton, graph.db.roles, i, stem)));
        written.gltf.push_back((folder.dir / (stem + ".glb")).string());
      }
    }
    if (folder.bvh) written.bvhFolder = folder.dir.string();
    if (folder.gltf) written.gltfFolder = folder.dir.string();
    if (folder.events) add(options.eventsOut.filename().string(), eventsText);
    json manifest = {{"format", kOutputFormat},
                     {"version", kOutputVersion},
                     {"run",
                      {{"scenario", scenario.path.string()},
                       {"graph_key", graph.key},
                       {"controller", options.controller},
                       {"policy", policyDir.string()},
                       {"avatars", avatars},
                       {"frames", frames},
                       {"seconds", static_cast<double>(frames) * model.frameTime},
                       {"seed", options.seed},
                       {"world", worldParamsJson(params)},
                       {"time_utc", utcNow()},
                       {"pid", ::getpid()},
                       {"tool_version", kVersion}}},
                     {"files", files}};
    // Events kept elsewhere: their hash says whether the file there is this run's.
    if (out.eventsScratch)
      manifest["events_out"] = {{"path", fs::absolute(options.eventsOut).lexically_normal().string()},
                                {"bytes", eventsText.size()},
                                {"hash", hexDigest(hashBytes(eventsText))}};
    manifest["hash"] = manifestHash(manifest);
    try {
      folder.bundle->commit(manifest.dump(2) + "\n");
    } catch (const Error& e) {
      throw Error(fmt::format("{} {}", folder.option, e.what()));
    }
    folder.created->keep();
  }
  if (out.eventsScratch) {
    std::error_code ec;
    fs::rename(eventsTemporary, options.eventsOut, ec);
    if (ec)
      throw Error(fmt::format("{} {}: could not move the events into place: {}", options.fields.eventsOut,
                              options.eventsOut.string(), ec.message()));
    out.eventsScratch->keep();
  }
  return written;
}

}  // namespace mgrl
