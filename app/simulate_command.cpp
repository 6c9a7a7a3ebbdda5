// `mgrl simulate` (DESIGN.md sec. 5): the world run headless (paper sec. 5, 6.6, 6.7):
// avatars in sparring pairs or with targets, controlled by the trained policy (or the
// online search, or at random), collisions at effective punches, reactions. Reports speed
// and hits; writes one BVH per avatar and the hits as JSON lines, atomically
// (mgrl/session/exports.hpp).
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
#include "mgrl/session/exports.hpp"
#include "mgrl/session/session.hpp"
#include "plugins.hpp"
#include "plural.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr long long kMaxAvatars = 1'000'000;
constexpr long long kMaxAvatarsWithPoses = 200'000;

// What a hit struck: the partner's body part, or the attacker's own target.
const char* struckName(const HitEvent& e) { return e.target < 0 ? "target" : bodyPartName(e.part); }

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

// Runs the world `frames` frames in slices of a second, so that long runs report progress
// (every 5 s); returns the wall time.
double runWorld(World& world, std::size_t frames, double frameTime, const WarningSink& log) {
  const auto start = Clock::now();
  auto lastReport = start;
  const std::size_t slice = std::max<std::size_t>(1, static_cast<std::size_t>(std::round(1.0 / frameTime)));
  for (std::size_t done = 0; done < frames;) {
    const std::size_t now = std::min(slice, frames - done);
    world.run(now);
    done += now;
    if (log && since(lastReport) >= 5 && done < frames) {
      lastReport = Clock::now();
      log(fmt::format("simulate: {:.0f} % ({:.1f} of {:.1f} s simulated), {}avatar-frames/s", 100.0 * done / frames,
                      done * frameTime, frames * frameTime,
                      humanCount(static_cast<double>(done * world.avatarCount()) / since(start))));
    }
  }
  return since(start);
}

// Landed hits by body part and, for up to 1000 avatars, by avatar; blocked strikes apart
// (both are in the events file).
void countHits(const World& world, std::size_t avatars, json& report) {
  std::vector<std::size_t> byAvatar(avatars, 0), blockedBy(avatars, 0);
  std::map<std::string, std::size_t> byPart = {{"head", 0}, {"chest", 0}, {"spine", 0}, {"target", 0}};
  for (const HitEvent& e : world.events()) {
    if (e.blocked) {
      ++blockedBy[e.attacker];
      continue;
    }
    ++byAvatar[e.attacker];
    ++byPart[struckName(e)];
  }
  report["hits_by_part"] = byPart;
  if (avatars <= 1000) {
    report["hits_by_avatar"] = byAvatar;
    report["blocked_by_avatar"] = blockedBy;
  }
}

// Hits landed by the first and by the second avatar of each sparring pair.
std::pair<std::size_t, std::size_t> landedBySide(const World& world) {
  std::size_t first = 0, second = 0;
  for (const HitEvent& e : world.events())
    if (!e.blocked) (e.attacker % 2 == 0 ? first : second) += 1;
  return {first, second};
}

}  // namespace

json runSimulate(const SimulateOptions& options) {
  checkSimulateOptions(options);
  const ControllerChoice choice{options.controller, options.horizon, options.horizonSeconds};
  const bool record = !options.bvhOut.empty() || !options.gltfOut.empty();
  const bool poses = options.poses || record;
  const ExportRequest exports{options.bvhOut,  options.gltfOut,    options.eventsOut, options.avatars,
                              options.seconds, options.controller, options.seed};
  Outputs out;
  SessionNeeds needs;
  needs.policy = choice.name == "policy" ? PolicyNeed::Required : PolicyNeed::None;
  needs.policyDir = options.policy;
  needs.beforeGraph = [&](const Scenario& scenario) { out = prepareOutputs(exports, scenario); };
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

  const double wall = runWorld(world, frames, model.frameTime, options.log);

  const WrittenFiles written = writeOutputs(out, exports, *session, world, frames);

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
                 {"hits", world.landedCount()},
                 {"hits_per_avatar_minute",
                  static_cast<double>(world.landedCount()) / static_cast<double>(avatars) / (simulated / 60)},
                 {"hits_by_part", json::object()},
                 {"blocked", world.blockedCount()},
                 {"decisions", world.decisions()},
                 {"bytes_per_avatar", world.bytesPerAvatar()},
                 {"bodies",
                  {{"restricted_decisions", world.bodyStats().restricted},
                   {"cornered_decisions", world.bodyStats().cornered},
                   {"pushes", world.bodyStats().pushes}}},
                 {"seed", options.seed},
                 {"world", worldParamsJson(params)}};
  countHits(world, avatars, report);
  if (options.controller == "policy") report["policy"] = policyDir.string();
  if (!options.partnerPolicy.empty()) {
    // Two policies spar: the hits each side landed (the first avatar of each pair plays
    // --policy, the second --partner-policy).
    const auto [first, second] = landedBySide(world);
    report["partner_policy"] = session->partnerPolicyDir.string();
    if (options.partnerRound > 0) report["partner_round"] = options.partnerRound;
    report["hits_by_side"] = {{"policy", first}, {"partner_policy", second}};
  } else if (params.mode == "sparring" && avatars >= 2 && !session->partnerName().empty()) {
    // An `opponent` scene: the second of each pair is the scripted opponent (issue 45).
    const auto [first, second] = landedBySide(world);
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
      "hits: {} ({:.1f} per avatar-minute; head {}, chest {}, spine {}, targets {}); blocked {}\n",
      r["controller"].get<std::string>(), r["mode"].get<std::string>(),
      counted(r["avatars"].get<std::size_t>(), "avatar"), counted(r["frames"].get<std::size_t>(), "frame"),
      r["seconds"].get<double>(), humanSeconds(r["wall_seconds"].get<double>()),
      humanCount(r["avatar_frames_per_second"].get<double>()), r["hits"].get<std::size_t>(),
      r["hits_per_avatar_minute"].get<double>(), r["hits_by_part"]["head"].get<std::size_t>(),
      r["hits_by_part"]["chest"].get<std::size_t>(), r["hits_by_part"]["spine"].get<std::size_t>(),
      r["hits_by_part"]["target"].get<std::size_t>(), r["blocked"].get<std::size_t>());
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
