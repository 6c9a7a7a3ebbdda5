// A world run headless on an open session (mgrl/session/simulate.hpp).
#include "mgrl/session/simulate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/numbers.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/session/graph_source.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

constexpr long long kMaxAvatars = 1'000'000;
constexpr long long kMaxAvatarsWithPoses = 200'000;

// What a hit struck: the partner's body part, or the attacker's own target.
const char* struckName(const HitEvent& e) { return e.target < 0 ? "target" : bodyPartName(e.part); }

}  // namespace

SimulateFields SimulateFields::keywords() {
  SimulateFields f;
  f.controller = {"controller", "horizon", "horizon_seconds"};
  f.exports = {"bvh_out", "gltf_out", "events_out", "avatars", "seconds"};
  f.avatars = "avatars";
  f.seconds = "seconds";
  f.topK = "top_k";
  f.threads = "threads";
  f.poses = "poses";
  f.policy = "tables";
  f.partnerPolicy = "partner_policy";
  f.partnerPolicyUsage = "partner_policy";
  f.partnerRound = "partner_round";
  f.round = "round";
  return f;
}

// Every mistake in the settings, found before anything is loaded.
void checkSimulateSettings(const ControllerRegistry& controllers, const SimulateSettings& options) {
  const SimulateFields& f = options.fields;
  checkControllerChoice(controllers, options.controller, f.controller);
  if (options.round > 0 && options.controller.name != "policy")
    throw Error(fmt::format("{}: expected {} policy (a self-play round's tables), found {}", f.round,
                            f.controller.controller, options.controller.name));
  if (options.avatars < 1 || options.avatars > kMaxAvatars)
    throw Error(
        fmt::format("{}: expected a number of avatars in [1, {}], found {}", f.avatars, kMaxAvatars, options.avatars));
  if ((options.poses || options.records()) && options.avatars > kMaxAvatarsWithPoses)
    throw Error(fmt::format("{}: expected at most {} avatars with poses ({}, {} or {}), found {}", f.avatars,
                            kMaxAvatarsWithPoses, f.poses, f.exports.bvhOut, f.exports.gltfOut, options.avatars));
  if (!(options.seconds > 0 && options.seconds <= 86400))
    throw Error(fmt::format("{}: expected simulated seconds in (0, 86400], found {}", f.seconds, options.seconds));
  if (options.topK < 0 || options.topK > 64)
    throw Error(
        fmt::format("{}: expected a number of candidates in [1, 64] (0: world.top_k), found {}", f.topK, options.topK));
  if (options.threads > 256)
    throw Error(fmt::format("{}: expected at most 256 threads, found {}", f.threads, options.threads));
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

json simulate(const Session& session, const SimulateSettings& settings, Outputs& outputs,
              const std::vector<PolicyPart>* policy) {
  if (!session.hasMotion())
    throw Error(
        "simulate: expected a session opened with the capture (SessionNeeds::motion), found one opened from the "
        "cached model alone: poses and bodies need the capture");
  const bool record = settings.records();
  const bool poses = settings.poses || record;
  const SimulateFields& f = settings.fields;
  Session::checkPartnerChoice(settings.partnerPolicy, settings.partnerRound, f.partnerRound, f.partnerPolicyUsage);
  if (!settings.partnerPolicy.empty()) {
    if (session.task.world.mode != "sparring")
      throw Error(fmt::format("{}: expected a sparring world (world.mode: sparring), found {}", f.partnerPolicy,
                              session.task.world.mode));
    if (settings.controller.name != "policy")
      throw Error(fmt::format("{}: expected {} policy (the first avatar of each pair plays {}), found {}",
                              f.partnerPolicy, f.controller.controller, f.policy, settings.controller.name));
  }
  if (settings.round > 0 && policy)
    throw Error(fmt::format("{}: expected the bundle's tables, found tables given by the caller", f.round));
  Policies played = policy               ? Policies(*policy)
                    : settings.round > 0 ? session.roundPolicies(settings.round)
                                         : session.policies();
  if (!settings.partnerPolicy.empty())
    played = session.withPartner(std::move(played), settings.partnerPolicy, settings.partnerRound);
  const fs::path& policyDir = session.policyDir;
  const Scenario& scenario = session.scenario;
  const GraphResult& graph = session.graph;
  const StateActionModel& model = session.model();
  const auto frames = static_cast<std::size_t>(std::max(1.0, std::round(settings.seconds / model.frameTime)));
  const auto avatars = static_cast<std::size_t>(settings.avatars);
  const std::size_t joints = graph.db.skeleton->jointCount();
  if (record) {
    const double bytes =
        recordingBytes(static_cast<double>(avatars) * static_cast<double>(frames), static_cast<double>(joints));
    if (bytes > kMaxRecordingBytes)
      throw Error(
          fmt::format("{}: recording {} avatars for {} frames needs about {:.1f} GB of memory; expected "
                      "at most {:.0f} GB: use fewer {} or {}",
                      settings.bvhOut.empty() ? f.exports.gltfOut : f.exports.bvhOut, avatars, frames, bytes / 1e9,
                      kMaxRecordingBytes / 1e9, f.avatars, f.seconds));
  }
  WorldSetup setup =
      session.worldSetup(avatars, settings.seed, settings.controller, played, static_cast<int>(settings.topK));
  const WorldParams& params = setup.params;
  setup.threads = settings.threads > 0 ? settings.threads : defaultThreadCount();
  setup.poses = poses;
  setup.record = record;
  World world(setup);
  const double startup = settings.startup ? settings.startup() : -1;

  const double wall = runWorld(world, frames, model.frameTime, settings.log);

  const WrittenFiles written = writeOutputs(outputs, settings.exportRequest(), session, world, frames);

  const double simulated = static_cast<double>(frames) * model.frameTime;
  json report = {{"scenario", scenario.path.string()},
                 {"controller", settings.controller.name},
                 {"mode", params.mode},
                 {"avatars", avatars},
                 {"frames", frames},
                 {"seconds", simulated},
                 {"fps", 1.0 / model.frameTime},
                 {"wall_seconds", wall},
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
                 {"seed", settings.seed},
                 {"world", worldParamsJson(params)}};
  if (startup >= 0) report["startup_seconds"] = startup;
  countHits(world, avatars, report);
  if (settings.controller.name == "policy" && !policy) report["policy"] = policyDir.string();
  if (settings.round > 0) report["round"] = settings.round;
  if (!settings.partnerPolicy.empty()) {
    // Two policies spar: the hits each side landed (the first avatar of each pair plays
    // --policy, the second --partner-policy).
    const auto [first, second] = landedBySide(world);
    report["partner_policy"] = played.partnerDir.string();
    if (settings.partnerRound > 0) report["partner_round"] = settings.partnerRound;
    report["hits_by_side"] = {{"policy", first}, {"partner_policy", second}};
  } else if (params.mode == "sparring" && avatars >= 2 && !session.partnerName(played).empty()) {
    // An `opponent` scene: the second of each pair is the scripted opponent.
    const auto [first, second] = landedBySide(world);
    report["partner"] = session.partnerName(played);
    report["hits_by_side"] = {{"avatars", first}, {"opponents", second}};
  }
  if (!written.bvh.empty()) {
    report["bvh_files"] = written.bvh;
    report["bvh_folder"] = written.bvhFolder;
    report["bvh_manifest"] = (settings.bvhOut / "manifest.json").string();
  }
  if (!written.gltf.empty()) {
    report["gltf_files"] = written.gltf;
    report["gltf_folder"] = written.gltfFolder;
    report["gltf_manifest"] = (settings.gltfOut / "manifest.json").string();
  }
  if (!settings.eventsOut.empty()) report["events_file"] = settings.eventsOut.string();
  return report;
}

}  // namespace mgrl
