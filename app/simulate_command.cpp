// `mgrl simulate` (DESIGN.md sec. 5): the world run headless (paper sec. 5, 6.6, 6.7):
// avatars in sparring pairs or with targets, controlled by the trained policy (or the
// online search, or at random), collisions at effective punches, reactions. Reports speed
// and hits; writes one BVH per avatar and the hits as JSON lines, atomically.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <signal.h>
#include <unistd.h>

#include <cerrno>

#include <fmt/format.h>

#include "learn_common.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/gltf.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"
#include "plugins.hpp"
#include "plural.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr long long kMaxAvatars = 1'000'000;
constexpr long long kMaxAvatarsWithPoses = 200'000;
constexpr double kMaxRecordingBytes = 4e9;

// A scratch folder for output, removed again with everything in it. If the output folder
// around it was made for this run, that goes too unless the run keeps its results
// (keep()): what a failed run leaves behind is nothing.
class ScratchDirectory {
 public:
  ScratchDirectory(fs::path path, fs::path created) : path_(std::move(path)), created_(std::move(created)) {}
  ~ScratchDirectory() {
    std::error_code ec;
    fs::remove_all(path_, ec);
    if (!created_.empty()) fs::remove_all(created_, ec);
  }
  ScratchDirectory(const ScratchDirectory&) = delete;
  ScratchDirectory& operator=(const ScratchDirectory&) = delete;
  const fs::path& path() const { return path_; }
  void keep() { created_.clear(); }

 private:
  fs::path path_;
  fs::path created_;  ///< the outermost folder this run created ("" none)
};

std::string scratchName() { return fmt::format(".mgrl-simulate-{}", ::getpid()); }

// Issue 19, defect 5: the scratch folders of runs that were killed (their process is gone)
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
    throw Error(fmt::format("{} {}: expected a writable folder, found one where files cannot be written", flag,
                            dir.string()));
  probe.close();
  fs::remove(scratch / "probe", ec);
  return guard;
}

// Issue 19, defect 6: --bvh-out's folder is one unit (a bundle, mgrl/core/bundle.hpp):
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

// Memory to record `avatarFrames` poses of `joints` joints for BVH export (bytes).
double recordingBytes(double avatarFrames, double joints) {
  return avatarFrames * (joints * (sizeof(Eigen::Quaterniond) + sizeof(Eigen::Vector3d)) + 64);
}

// What a hit struck: the partner's body part, or the attacker's own target.
const char* struckName(const HitEvent& e) { return e.target < 0 ? "target" : bodyPartName(e.part); }

std::string eventLine(const HitEvent& e) { return hitEventJson(e).dump(); }

}  // namespace

// Every mistake in the command line, found before anything is loaded.
void checkSimulateOptions(const SimulateOptions& options) {
  checkControllerChoice({options.controller, options.horizon, options.horizonSeconds});
  if (options.avatars < 1 || options.avatars > kMaxAvatars)
    throw Error(fmt::format("--avatars: expected a number of avatars in [1, {}], found {}", kMaxAvatars,
                            options.avatars));
  if ((options.poses || !options.bvhOut.empty() || !options.gltfOut.empty()) && options.avatars > kMaxAvatarsWithPoses)
    throw Error(
        fmt::format("--avatars: expected at most {} avatars with poses (--poses, --bvh-out or --gltf-out), "
                    "found {}",
                    kMaxAvatarsWithPoses, options.avatars));
  if (!(options.seconds > 0 && options.seconds <= 86400))
    throw Error(fmt::format("--seconds: expected simulated seconds in (0, 86400], found {}", options.seconds));
  if (options.topK < 0 || options.topK > 64)
    throw Error(fmt::format("--top-k: expected a number of candidates in [1, 64] (0: world.top_k), found {}",
                            options.topK));
  if (options.threads > 256)
    throw Error(fmt::format("--threads: expected at most 256 threads, found {}", options.threads));
}

namespace {

// Where the run's outputs go: checked, and their scratch folders made, before anything is
// simulated (and removed again if the run fails).
// One output folder (--bvh-out, --gltf-out, or both when they name the same folder): one
// unit, written beside it and swapped in whole with its manifest.
struct OutputFolder {
  std::string option;  ///< "--bvh-out", "--gltf-out" or "--bvh-out and --gltf-out"
  fs::path dir;        ///< as given
  bool bvh = false, gltf = false, events = false;
  std::unique_ptr<ScratchDirectory> created;
  std::unique_ptr<BundleWriter> bundle;
};
struct Outputs {
  std::vector<OutputFolder> folders;
  std::unique_ptr<ScratchDirectory> eventsScratch;  ///< --events-out outside every output folder
};

// A folder argument as an absolute, normal path without a trailing separator.
fs::path folderOf(const fs::path& p) {
  fs::path absolute = fs::absolute(p).lexically_normal();
  return absolute.has_filename() ? absolute : absolute.parent_path();
}

// avatar_NNN.bvh or avatar_NNN.glb: the name of a file an output folder holds per avatar.
bool avatarFileName(std::string_view name) {
  return name.rfind("avatar_", 0) == 0 && (name.ends_with(".bvh") || name.ends_with(".glb"));
}

Outputs prepareOutputs(const SimulateOptions& options, const Scenario& scenario) {
  Outputs out;
  if (!options.bvhOut.empty()) {
    OutputFolder& folder = out.folders.emplace_back();
    folder.option = "--bvh-out";
    folder.dir = options.bvhOut;
    folder.bvh = true;
  }
  if (!options.gltfOut.empty()) {
    if (!out.folders.empty() && folderOf(options.gltfOut) == folderOf(options.bvhOut)) {
      out.folders.front().gltf = true;  // one folder, one unit, both formats
      out.folders.front().option = "--bvh-out and --gltf-out";
    } else {
      OutputFolder& folder = out.folders.emplace_back();
      folder.option = "--gltf-out";
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
      throw Error(fmt::format("--events-out {}: expected a file name, found a folder", options.eventsOut.string()));
    // A missing folder is made, as for --bvh-out (prepareFolder and prepareBundle below).
  }
  if (!out.folders.empty()) {
    // A first estimate with a small skeleton (20 joints), exact once the skeleton is known.
    const double avatarFrames = static_cast<double>(options.avatars) * std::round(options.seconds * scenario.motion.fps);
    if (recordingBytes(avatarFrames, 20) > kMaxRecordingBytes)
      throw Error(
          fmt::format("{}: recording {} avatars for {} s needs more than {:.1f} GB of memory; expected "
                      "at most {:.0f} GB: use fewer --avatars or --seconds",
                      out.folders.front().option, options.avatars, options.seconds,
                      recordingBytes(avatarFrames, 20) / 1e9, kMaxRecordingBytes / 1e9));
  }
  if (eventsFolder) {
    const std::string name = options.eventsOut.filename().string();
    if (name == "manifest.json" || avatarFileName(name))
      throw Error(
          fmt::format("--events-out {}: expected a name other than the {} folder's own files "
                      "(manifest.json, avatar_NNN.bvh, avatar_NNN.glb), found {}",
                      options.eventsOut.string(), eventsFolder->option, quoteToken(name)));
  }
  if (!options.eventsOut.empty() && !eventsFolder) {
    const fs::path parent = options.eventsOut.parent_path().empty() ? fs::path(".") : options.eventsOut.parent_path();
    out.eventsScratch = prepareFolder(parent, "--events-out");
  }
  for (OutputFolder& folder : out.folders) folder.bundle = prepareBundle(folder.dir, folder.created, folder.option);
  return out;
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

struct WrittenFiles {
  std::vector<std::string> bvh, gltf;
  std::string bvhFolder, gltfFolder;
};

// Writes the run's outputs into the bundles' temporaries and the scratch folder, then puts
// them in place: each output folder whole (with the events if they belong to it), then the
// events. Returns the motion files written.
WrittenFiles writeOutputs(Outputs& out, const SimulateOptions& options, const Session& session, const World& world,
                          std::size_t frames) {
  const StateActionModel& model = session.model();
  const std::size_t avatars = world.avatarCount();
  const Scenario& scenario = session.scenario;
  const GraphResult& graph = session.graph;
  const WorldParams& params = session.task.world;
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
    json manifest = {
        {"format", kOutputFormat},
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
    if (ec) throw Error(fmt::format("--events-out {}: could not move the events into place: {}",
                                    options.eventsOut.string(), ec.message()));
    out.eventsScratch->keep();
  }
  return written;
}

}  // namespace

json runSimulate(const SimulateOptions& options) {
  checkSimulateOptions(options);
  const ControllerChoice choice{options.controller, options.horizon, options.horizonSeconds};
  const bool record = !options.bvhOut.empty() || !options.gltfOut.empty();
  const bool poses = options.poses || record;
  Outputs out;
  SessionNeeds needs;
  needs.policy = choice.name == "policy" ? PolicyNeed::Required : PolicyNeed::None;
  needs.policyDir = options.policy;
  needs.beforeGraph = [&](const Scenario& scenario) { out = prepareOutputs(options, scenario); };
  const std::unique_ptr<Session> session = openSession(options, needs);
  if (options.topK > 0) session->task.world.variety.topK = static_cast<int>(options.topK);
  const WorldParams& params = session->task.world;
  if (!options.partnerPolicy.empty()) {
    if (params.mode != "sparring")
      throw Error(
          fmt::format("--partner-policy: expected a sparring world (world.mode: sparring), found {}", params.mode));
    if (choice.name != "policy")
      throw Error(
          fmt::format("--partner-policy: expected --controller policy (the first avatar of each pair plays "
                      "--policy), found {}",
                      choice.name));
    session->loadPartnerPolicy(options.partnerPolicy, options.partnerRound);
  } else if (options.partnerRound > 0) {
    throw Error("--partner-round: expected --partner-policy DIR as well (the bundle whose round the partner plays)");
  }
  const fs::path& policyDir = session->policyDir;
  const Scenario& scenario = session->scenario;
  const GraphResult& graph = session->graph;
  const StateActionModel& model = session->model();
  const auto frames = static_cast<std::size_t>(std::max(1.0, std::round(options.seconds / model.frameTime)));
  const auto avatars = static_cast<std::size_t>(options.avatars);
  const std::size_t joints = graph.db.skeleton->jointCount();
  if (record) {
    const double bytes =
        recordingBytes(static_cast<double>(avatars) * static_cast<double>(frames), static_cast<double>(joints));
    if (bytes > kMaxRecordingBytes)
      throw Error(fmt::format(
          "{}: recording {} avatars for {} frames needs about {:.1f} GB of memory; expected "
          "at most {:.0f} GB: use fewer --avatars or --seconds",
          options.bvhOut.empty() ? "--gltf-out" : "--bvh-out", avatars, frames, bytes / 1e9, kMaxRecordingBytes / 1e9));
  }
  WorldSetup setup = session->worldSetup(avatars, options.seed, choice);
  setup.threads = options.threads > 0 ? options.threads : defaultThreadCount();
  setup.poses = poses;
  setup.record = record;
  World world(setup);
  const double startup = secondsSinceStart();

  // Run in slices so that long runs report progress (stderr, every 5 s).
  const auto start = Clock::now();
  auto lastReport = start;
  const std::size_t slice = std::max<std::size_t>(1, static_cast<std::size_t>(std::round(1.0 / model.frameTime)));
  for (std::size_t done = 0; done < frames;) {
    const std::size_t now = std::min(slice, frames - done);
    world.run(now);
    done += now;
    if (options.log && since(lastReport) >= 5 && done < frames) {
      lastReport = Clock::now();
      options.log(fmt::format("simulate: {:.0f} % ({:.1f} of {:.1f} s simulated), {}avatar-frames/s", 100.0 * done / frames,
                              done * model.frameTime, frames * model.frameTime,
                              humanCount(static_cast<double>(done * avatars) / since(start))));
    }
  }
  const double wall = since(start);

  const WrittenFiles written = writeOutputs(out, options, *session, world, frames);

  std::vector<std::size_t> byAvatar(avatars, 0);
  std::map<std::string, std::size_t> byPart = {{"head", 0}, {"chest", 0}, {"spine", 0}, {"target", 0}};
  for (const HitEvent& e : world.events()) {
    ++byAvatar[e.attacker];
    ++byPart[struckName(e)];
  }
  const double simulated = static_cast<double>(frames) * model.frameTime;
  json report = {{"scenario", scenario.path.string()},
                 {"controller", options.controller},
                 {"mode", params.mode},
                 {"avatars", avatars},
                 {"frames", frames},
                 {"seconds", simulated},
                 {"fps", 1.0 / model.frameTime},
                 {"wall_seconds", wall},
                 {"startup_seconds", startup},
                 {"avatar_frames_per_second", static_cast<double>(frames * avatars) / std::max(wall, 1e-9)},
                 {"poses", poses},
                 {"hits", world.events().size()},
                 {"hits_per_avatar_minute",
                  static_cast<double>(world.events().size()) / static_cast<double>(avatars) / (simulated / 60)},
                 {"hits_by_part", byPart},
                 {"decisions", world.decisions()},
                 {"bytes_per_avatar", world.bytesPerAvatar()},
                 {"bodies",
                  {{"restricted_decisions", world.bodyStats().restricted},
                   {"cornered_decisions", world.bodyStats().cornered},
                   {"pushes", world.bodyStats().pushes}}},
                 {"seed", options.seed},
                 {"world", worldParamsJson(params)}};
  if (avatars <= 1000) report["hits_by_avatar"] = byAvatar;
  if (options.controller == "policy") report["policy"] = policyDir.string();
  if (!options.partnerPolicy.empty()) {
    // Two policies spar: the hits each side landed (the first avatar of each pair plays
    // --policy, the second --partner-policy).
    std::size_t first = 0, second = 0;
    for (const HitEvent& e : world.events()) (e.attacker % 2 == 0 ? first : second) += 1;
    report["partner_policy"] = session->partnerPolicyDir.string();
    if (options.partnerRound > 0) report["partner_round"] = options.partnerRound;
    report["hits_by_side"] = {{"policy", first}, {"partner_policy", second}};
  } else if (params.mode == "sparring" && avatars >= 2 && !session->partnerName().empty()) {
    // An `opponent` scene: the second of each pair is the scripted opponent (issue 45).
    std::size_t first = 0, second = 0;
    for (const HitEvent& e : world.events()) (e.attacker % 2 == 0 ? first : second) += 1;
    report["partner"] = session->partnerName();
    report["hits_by_side"] = {{"avatars", first}, {"opponents", second}};
  }
  if (!written.bvh.empty()) {
    report["bvh_files"] = written.bvh;
    report["bvh_folder"] = written.bvhFolder;
    report["bvh_manifest"] = (options.bvhOut / "manifest.json").string();
  }
  if (!written.gltf.empty()) {
    report["gltf_files"] = written.gltf;
    report["gltf_folder"] = written.gltfFolder;
    report["gltf_manifest"] = (options.gltfOut / "manifest.json").string();
  }
  if (!options.eventsOut.empty()) report["events_file"] = options.eventsOut.string();
  return report;
}

std::string simulateText(const json& r) {
  std::string text = fmt::format(
      "simulate ({} controller, {}): {} x {} ({:.1f} s) in {}: {}avatar-frames/s\n"
      "hits: {} ({:.1f} per avatar-minute; head {}, chest {}, spine {}, targets {})\n",
      r["controller"].get<std::string>(), r["mode"].get<std::string>(),
      counted(r["avatars"].get<std::size_t>(), "avatar"), counted(r["frames"].get<std::size_t>(), "frame"),
      r["seconds"].get<double>(), humanSeconds(r["wall_seconds"].get<double>()),
      humanCount(r["avatar_frames_per_second"].get<double>()), r["hits"].get<std::size_t>(),
      r["hits_per_avatar_minute"].get<double>(), r["hits_by_part"]["head"].get<std::size_t>(),
      r["hits_by_part"]["chest"].get<std::size_t>(), r["hits_by_part"]["spine"].get<std::size_t>(),
      r["hits_by_part"]["target"].get<std::size_t>());
  if (r.contains("partner"))
    text += fmt::format("sides: the avatars landed {}, their scripted opponents ({}) landed {}\n",
                        r["hits_by_side"]["avatars"].get<std::size_t>(), r["partner"].get<std::string>(),
                        r["hits_by_side"]["opponents"].get<std::size_t>());
  else if (r.contains("hits_by_side"))
    text += fmt::format("sides: {} landed {}, {} (the partners) landed {}\n", r["policy"].get<std::string>(),
                        r["hits_by_side"]["policy"].get<std::size_t>(), r["partner_policy"].get<std::string>(),
                        r["hits_by_side"]["partner_policy"].get<std::size_t>());
  if (r.contains("bvh_files"))
    text += fmt::format("wrote {} to {}\n", counted(r["bvh_files"].size(), "BVH file"),
                        r["bvh_folder"].get<std::string>());
  if (r.contains("gltf_files"))
    text += fmt::format("wrote {} to {}\n", counted(r["gltf_files"].size(), "glTF file"),
                        r["gltf_folder"].get<std::string>());
  if (r.contains("events_file")) text += fmt::format("wrote the hits to {}\n", r["events_file"].get<std::string>());
  return text;
}

}  // namespace mgrl::app
