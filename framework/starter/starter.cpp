#include "mgrl/starter/starter.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <span>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/graph_source.hpp"

namespace mgrl {
namespace {

namespace fs = std::filesystem;

// The graph settings init tries, in order: the paper's contact event first, then any
// contact change (more transition points), each from the paper's threshold up. The first
// that keeps kKeepShare of the frames in at least kMinStates states wins: lower
// thresholds blend more alike poses. A library (longer than GraphParams::kLibrarySeconds,
// whose graph is bounded and cut where the performer stands still) tries any contact change
// first, for actions a fraction of a second long, and must keep kLibraryKeepShare.
constexpr double kThresholds[] = {0.45, 0.6, 0.75, 0.9, 1.2};
constexpr ContactEvent kEvents[] = {ContactEvent::LeftFootLiftoff, ContactEvent::AnyContactChange};
constexpr ContactEvent kLibraryEvents[] = {ContactEvent::AnyContactChange, ContactEvent::LeftFootLiftoff};
constexpr double kKeepShare = 0.6;
constexpr double kLibraryKeepShare = 0.8;

// A library whose frames travel at least this fast (net, over 3 s) this often holds
// locomotion first: its behaviour is walking to a goal, whatever strikes it also holds.
constexpr double kLocomotion_mps = 0.5;
constexpr double kLocomotionShare = 0.25;

// The share of frames at which the body travels kLocomotion_mps or faster: the root's net
// ground displacement over the 3 s around the frame (inside its clip), per second.
double locomotionShare(const MotionDatabase& db) {
  const auto half = static_cast<std::size_t>(std::lround(1.5 / db.frameTime));
  std::size_t moving = 0;
  for (const Clip& clip : db.clips) {
    const std::vector<AvatarFrame>& frames = clip.annotation.frames;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const std::size_t a = f > half ? f - half : 0, b = std::min(frames.size() - 1, f + half);
      if (b <= a) continue;
      const Eigen::Vector3d d = frames[b].origin - frames[a].origin;
      moving += std::hypot(d.x(), d.z()) / (static_cast<double>(b - a) * db.frameTime) >= kLocomotion_mps ? 1 : 0;
    }
  }
  return db.frameCount() ? static_cast<double>(moving) / db.frameCount() : 0;
}

bool isLibrary(const MotionDatabase& db) { return db.frameCount() * db.frameTime > GraphParams::kLibrarySeconds; }
double keepShare(const MotionDatabase& db) { return isLibrary(db) ? kLibraryKeepShare : kKeepShare; }
constexpr int kMinStates = 10;
// Fewer effective strikes inside the graph's actions than this, and the capture has nothing
// to learn to hit with.
constexpr std::size_t kMinStrikes = 5;
// Arms swinging while the body walks or runs this fast are not punches
// (AnnotationParams::swingTravel_mps): a starter scenario may hold a library's locomotion.
constexpr double kSwingTravel_mps = 0.9;

struct GraphTry {
  double threshold = 0;
  ContactEvent event = ContactEvent::LeftFootLiftoff;
  std::size_t keptFrames = 0, states = 0, actions = 0, hits = 0, kicks = 0;
  double p90ActionTravel = 0;  ///< 90th percentile of the actions' ground displacement (m)
  std::string failure;         ///< why the build failed, if it did

  double share(std::size_t frames) const { return frames ? static_cast<double>(keptFrames) / frames : 0; }
  bool usable(const MotionDatabase& db) const {
    return failure.empty() && share(db.frameCount()) >= keepShare(db) && states >= static_cast<std::size_t>(kMinStates);
  }
};

GraphTry tryGraph(const MotionDatabase& db, double threshold, ContactEvent event) {
  GraphTry t;
  t.threshold = threshold;
  t.event = event;
  GraphParams params;
  params.threshold = threshold;
  params.contactEvent = event;
  params.minStates = 1;
  try {
    const StateActionModel m = buildStateActionModel(db, params);
    t.keptFrames = m.componentFrames.size();
    t.states = m.stateCount();
    t.actions = m.actionCount();
    t.hits = m.hits.size();
    t.kicks = m.kicks.size();
    std::vector<double> travel;
    for (std::size_t a = 0; a < m.actionCount(); ++a)
      travel.push_back(std::hypot(m.actionDisplacement[3 * a], m.actionDisplacement[3 * a + 1]));
    if (!travel.empty()) {
      const std::size_t k = travel.size() * 9 / 10;
      std::nth_element(travel.begin(), travel.begin() + static_cast<std::ptrdiff_t>(k), travel.end());
      t.p90ActionTravel = travel[k];
    }
  } catch (const Error& e) {
    t.failure = e.what();
  }
  return t;
}

// How the scenario names a file: beside the scenario, else under the data folder, else as
// an absolute path (scenarios/README.md: relative paths are looked up in that order).
std::string scenarioPathOf(const fs::path& file, const fs::path& scenarioDir, const fs::path& dataDir) {
  const fs::path absolute = fs::weakly_canonical(fs::absolute(file));
  for (const fs::path& base : {scenarioDir, dataDir}) {
    if (base.empty()) continue;
    std::error_code ec;
    const fs::path root = fs::weakly_canonical(fs::absolute(base), ec);
    if (ec) continue;
    const fs::path relative = absolute.lexically_relative(root);
    if (!relative.empty() && *relative.begin() != "..") return relative.generic_string();
  }
  return absolute.generic_string();
}

std::string defaultName(const fs::path& file) {
  std::string name;
  for (const char c : file.stem().string())
    name += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(static_cast<unsigned char>(c)))
                                                        : '_';
  return name.empty() ? std::string("capture") : name;
}

// A YAML double-quoted string.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

double roundUpTo(double value, double step) { return std::ceil(value / step - 1e-9) * step; }

// The graphs tried, from the paper's threshold and contact event up, until one is usable.
std::vector<GraphTry> tryGraphs(const MotionDatabase& db, const std::function<void(const std::string&)>& log) {
  std::vector<GraphTry> tries;
  for (const ContactEvent event :
       isLibrary(db) ? std::span<const ContactEvent>(kLibraryEvents) : std::span<const ContactEvent>(kEvents)) {
    for (const double threshold : kThresholds) {
      tries.push_back(tryGraph(db, threshold, event));
      const GraphTry& t = tries.back();
      log(fmt::format("init: graph at threshold {:g}, {}: {:.0f} % of frames kept, {} states, {} actions", threshold,
                      contactEventName(event), 100 * t.share(db.frameCount()), t.states, t.actions));
      if (t.usable(db)) return tries;
    }
  }
  return tries;
}

// The usable graph tried last, else the one that kept most frames; throws when none has
// two states.
const GraphTry* chooseGraph(const MotionDatabase& db, const std::vector<GraphTry>& tries) {
  if (tries.back().usable(db)) return &tries.back();
  const auto best = std::max_element(tries.begin(), tries.end(), [&](const GraphTry& a, const GraphTry& b) {
    return a.share(db.frameCount()) < b.share(db.frameCount());
  });
  if (best->states < 2)
    throw Error(
        fmt::format("init: expected a graph of at least {} states from these files, found at most {} at "
                    "any threshold up to {:g} ({} frames, {:.1f} s: too little capture, or poses too unalike "
                    "to join); add more capture of one person",
                    kMinStates, best->states, kThresholds[std::size(kThresholds) - 1], db.frameCount(),
                    db.frameCount() * db.frameTime));
  return &*best;
}

// The behaviours section for what the capture can do: the paper's two behaviours for
// punches, a kick, or walking to a goal (for a library of locomotion, whose share of
// travelling frames is locomotionShare; -1 for other capture).
std::string behaviorsYaml(const std::string& kind, const GraphTry& chosen, double approachRadius, double goalRadius,
                          double locomotionShare) {
  std::string y;
  y += "behaviors:\n";
  if (kind == "punch") {
    y += fmt::format(
        "  # The paper's two behaviours (sec. 6.4). The graph's actions hold {} effective hitting\n"
        "  # points (sec. 6.2). Approach's grid reaches three of the longer actions ({:.2f} m each).\n",
        chosen.hits, chosen.p90ActionTravel);
    y += "  approach:\n"
         "    description: bring the effective hitting points' centroid to the target\n"
         "    weight: 1\n"
         "    activation: always\n";
    y += fmt::format("    discretizer: {{type: polar2d, radius: {:g}, rings: 5, sectors: 13}}\n", approachRadius);
    y += "    reward: {type: approach, sigma: 0.10, gamma: 0.97}\n"
         "    learner: {type: value_iteration}\n"
         "  # Weighted 5: approach pays every action, hit once per landed punch (boxing.yaml).\n"
         "  hit:\n"
         "    description: land an effective punch on the target\n"
         "    weight: 5\n"
         "    activation: target_inside\n"
         "    # Over the volume where this capture's punches land.\n"
         "    discretizer: {type: cylindrical3d, angles: 20, distances: 16, heights: 6, bounds: hits}\n"
         "    reward: {type: hit, contact_radius: 0.15, gamma: 0.97}\n"
         "    learner: {type: value_iteration}\n";
  } else if (kind == "kick") {
    y += fmt::format("  # The graph's actions hold {} effective kick frames and too few punches.\n", chosen.kicks);
    y += "  kick:\n"
         "    description: land an effective kick of either foot within 0.3 m of the target\n"
         "    discretizer: {type: cylindrical3d, bounds: given, angles: 16, angle_min: -180, angle_max: 180,\n"
         "                  distances: 10, distance_min: 0.3, distance_max: 2.5, heights: 4, height_min: 0.4,\n"
         "                  height_max: 1.3}\n"
         "    reward:\n"
         "      type: terms\n"
         "      gamma: 0.97\n"
         "      terms:\n"
         "        - {term: contact, effector: feet, radius: 0.3}\n"
         "    learner: {type: value_iteration}\n"
         "    success: {term: contact}\n\n"
         "# Where eval and simulate put targets: 0.6 m above the ground.\n"
         "world:\n"
         "  mode: targets\n"
         "  target_height: 0.6\n";
  } else {
    if (locomotionShare >= 0)
      y += fmt::format(
          "  # A library of locomotion: the body travels {:.0f} % of the time. Its {} effective hitting\n"
          "  # points could train the paper's approach and hit too (docs/own-capture.md).\n",
          100 * locomotionShare, chosen.hits);
    else
      y += "  # The capture has too few effective punches or kicks to learn striking: walk to a goal.\n";
    y += "  goal:\n"
         "    description: pelvis on the goal point, then stay\n";
    y += fmt::format("    discretizer: {{type: polar2d, radius: {:g}, rings: 9, sectors: 13}}\n", goalRadius);
    y += "    reward:\n"
         "      type: terms\n"
         "      combine: sum\n"
         "      gamma: 0.97\n"
         "      terms:\n"
         "        - {term: distance, point: pelvis, sigma: 0.3}\n"
         "    learner: {type: value_iteration}\n"
         "    success: {term: distance, within: 0.3, hold_s: 1}\n";
  }
  return y;
}

// Writes the scenario text to `out` only once it loads as a scenario (and its behaviours
// check out): staged beside it, then renamed into place.
void writeCheckedScenario(const fs::path& out, const std::string& y, const fs::path& dataDir, const Plugins& plugins) {
  const fs::path staging = out.parent_path() / (out.filename().string() + ".init-check.yaml");
  writeFileAtomically(staging, y);
  try {
    const Scenario scenario = loadScenario(staging, dataDir);
    checkBehaviors(scenario, plugins);
  } catch (const Error& e) {
    std::error_code ec;
    fs::remove(staging, ec);
    throw Error(fmt::format("init: internal error: the scenario written for these files does not load: {}", e.what()));
  }
  std::error_code ec;
  fs::rename(staging, out, ec);
  if (ec) {
    fs::remove(staging, ec);
    throw Error(fmt::format("init: cannot write {}: {}", out.string(), ec.message()));
  }
}

// The roles found, as comments the user can uncomment to set one.
std::string rolesYaml(const MotionDatabase& db, const RoleOverrides& setRoles) {
  std::string y;
  y += "  # Roles, found by joint name (uncomment a line to set one yourself):\n";
  const std::vector<std::string> roleList = roleNames();
  const std::vector<int> roleJoints = roleJointIndices(db.roles);
  y += "  # roles:\n";
  for (std::size_t r = 0; r < roleList.size(); ++r) {
    const bool set = setRoles.count(roleList[r]) > 0;
    const std::string joint = db.skeleton->joint(static_cast<std::size_t>(roleJoints[r])).name;
    std::string note = set ? "set with --role" : "found by name";
    if ((r == 0 || r == 1) && roleJoints[r] == roleJoints[r + 2] && !set)
      note = "guessed: no fist or finger joint, the wrist stands in (its end site is the fist tip)";
    if (roleList[r] == "pelvis" && db.rootMotion.joint != 0) note += "; carries the root motion";
    const std::string line = fmt::format("  #   {}: {}", roleList[r], joint);
    y += fmt::format("{:<40} # {}\n", line, note);
  }
  return y;
}

// The graph section, with the settings tried as comments.
std::string graphYaml(const MotionDatabase& db, const std::vector<GraphTry>& tries, const GraphTry& chosen) {
  std::string y;
  if (isLibrary(db)) {
    y += fmt::format("# A library ({:.0f} minutes of capture, more than {:g}): its graph keeps at most {} actions a\n",
                     db.frameCount() * db.frameTime / 60, GraphParams::kLibrarySeconds / 60,
                     GraphParams::kLibraryOutDegree);
    y += "# state and is also cut where the performer stands still (max_out_degree: auto and\n";
    y += "# standing_cuts: auto; `mgrl graph` reports what they did). Chosen by trying thresholds from\n";
    y += "# the paper's 0.45 up, any contact change first (short actions),";
  } else {
    y += "# Chosen by trying thresholds from the paper's 0.45 up, with the paper's contact event\n";
    y += "# first,";
  }
  y += fmt::format(" until the largest component kept {:.0f} % of the frames in {} states or more:\n",
                   100 * keepShare(db), kMinStates);
  for (const GraphTry& t : tries)
    y += fmt::format("#   threshold {:<4g} {:<18} {}\n", t.threshold, contactEventName(t.event),
                     t.failure.empty() ? fmt::format("{:3.0f} % kept, {} states, {} actions",
                                                     100 * t.share(db.frameCount()), t.states, t.actions)
                                       : std::string("no graph"));
  y += "graph:\n";
  y += fmt::format("  threshold: {:g}\n  contact_event: {}\n  min_states: {}\n\n", chosen.threshold,
                   contactEventName(chosen.event), std::min<std::size_t>(kMinStates, chosen.states));
  return y;
}

}  // namespace

nlohmann::json runInit(const InitOptions& options) {
  if (options.files.empty()) throw Error("init: expected at least one motion file, found none");
  const auto log = [&](const std::string& message) {
    if (options.log) options.log(message);
  };
  const std::string name = !options.name.empty()  ? options.name
                           : !options.out.empty() ? defaultName(options.out)
                                                  : defaultName(options.files.front());
  const fs::path out = options.out.empty() ? fs::path(name + ".yaml") : options.out;
  if (fs::exists(out) && !options.force)
    throw Error(fmt::format("init: {} already exists; expected a new file (--force replaces it)", out.string()));
  // Before any work: the folder it goes into must be there.
  if (const fs::path folder = fs::absolute(out).parent_path(); !fs::is_directory(folder))
    throw Error(fmt::format("init: --out {}: expected an existing folder to write into, found no folder {}",
                            out.string(), folder.string()));
  if (!(options.fps > 0 && options.fps <= 1000))
    throw Error(fmt::format("--fps: expected a frame rate in (0, 1000], found {}", options.fps));

  // The capture, loaded and annotated as `mgrl graph` will.
  std::vector<std::string> warnings;
  const WarningSink warn = [&](const std::string& message) { warnings.push_back(message); };
  MotionSpec spec;
  spec.fps = options.fps;
  spec.units = options.units;
  spec.roles = options.roles;
  spec.annotation.swingTravel_mps = kSwingTravel_mps;
  std::vector<std::pair<std::string, Motion>> motions;
  std::vector<std::string> units;
  for (const fs::path& file : options.files) {
    LoadOptions load;
    load.units = options.units;
    load.fps = options.fps;
    load.warn = warn;
    LoadedMotion loaded = loadMotion(file, load);
    units.emplace_back(lengthUnitName(loaded.units));
    spec.files.push_back(file);
    motions.emplace_back(file.filename().string(), std::move(loaded.motion));
  }
  const MotionDatabase db = makeMotionDatabase(std::move(motions), spec, warn);
  std::size_t strikes = 0, kicks = 0;
  double minHeight = 1e300, maxHeight = 0;
  for (const Clip& clip : db.clips) {
    strikes += static_cast<std::size_t>(clip.annotation.punches[0] + clip.annotation.punches[1]);
    kicks += static_cast<std::size_t>(clip.annotation.kickCount[0] + clip.annotation.kickCount[1]);
    minHeight = std::min(minHeight, clip.annotation.standingHeight);
    maxHeight = std::max(maxHeight, clip.annotation.standingHeight);
  }
  log(fmt::format("init: {} frames in {} file{} at {:g} fps ({:.1f} s); {} effective punches, {} kicks",
                  db.frameCount(), db.clips.size(), db.clips.size() == 1 ? "" : "s", options.fps,
                  db.frameCount() * db.frameTime, strikes, kicks));

  // The graph: the first setting that keeps most frames in enough states.
  const std::vector<GraphTry> tries = tryGraphs(db, log);
  const GraphTry* chosen = chooseGraph(db, tries);

  // Behaviours the capture can do.
  const double travelling = locomotionShare(db);
  const bool locomotion = isLibrary(db) && travelling >= kLocomotionShare;
  const std::string kind = locomotion                     ? "goal"
                           : chosen->hits >= kMinStrikes  ? "punch"
                           : chosen->kicks >= kMinStrikes ? "kick"
                                                          : "goal";
  // Approach's grid: three of the longer actions (their 90th percentile), 2 to 4 m (the paper's is 2 m).
  const double approachRadius = std::clamp(roundUpTo(3 * chosen->p90ActionTravel, 0.5), 2.0, 4.0);
  const double goalRadius = std::clamp(roundUpTo(6 * chosen->p90ActionTravel, 0.5), 2.0, 6.0);

  const fs::path scenarioDir = fs::absolute(out).parent_path();
  std::string y;
  std::vector<std::string> names;
  for (const fs::path& f : options.files) names.push_back(f.filename().string());
  if (names.size() > 3) names = {names.front(), "...", names.back()};
  y += fmt::format("# Starter scenario written by `mgrl init` for {}.\n", fmt::join(names, ", "));
  y += "# Every key is explained in scenarios/README.md; docs/own-capture.md says what init detects.\n";
  y += fmt::format("name: {}\n", name);
  y += fmt::format("description: {}\n\n", quoted(fmt::format("{} s of capture in {} file{}, started by mgrl init",
                                                             fmt::format("{:.0f}", db.frameCount() * db.frameTime),
                                                             db.clips.size(), db.clips.size() == 1 ? "" : "s")));
  y += "motion:\n  files:\n";
  for (const fs::path& file : options.files)
    y += fmt::format("    - {}\n", quoted(scenarioPathOf(file, scenarioDir, options.dataDir)));
  y += fmt::format("  fps: {:g}\n", options.fps);
  std::vector<std::string> distinctUnits = units;
  std::sort(distinctUnits.begin(), distinctUnits.end());
  distinctUnits.erase(std::unique(distinctUnits.begin(), distinctUnits.end()), distinctUnits.end());
  if (options.units == LengthUnit::Auto && distinctUnits.size() == 1)
    y += fmt::format("  # Detected from the skeleton's size: standing heights {:.2f} to {:.2f} m in {}.\n", minHeight,
                     maxHeight, distinctUnits.front());
  y += fmt::format("  units: {}\n", options.units == LengthUnit::Auto && distinctUnits.size() == 1
                                        ? distinctUnits.front()
                                        : std::string(lengthUnitName(options.units)));
  y += fmt::format("  # {}.\n", db.rootMotion.sentence);
  y += rolesYaml(db, options.roles);
  y += "  annotation:\n";
  y += "    # Arms that swing while the body walks or runs this fast (m/s, over 3 s) are not punches\n";
  y += "    # unless the fist drives away from the shoulder; 0 counts them (docs/own-capture.md).\n";
  y += fmt::format("    swing_travel_mps: {:g}\n", kSwingTravel_mps);
  y += "\n";
  y += graphYaml(db, tries, *chosen);
  y += behaviorsYaml(kind, *chosen, approachRadius, goalRadius, locomotion ? travelling : -1);

  writeCheckedScenario(out, y, options.dataDir, requirePlugins(options.plugins, "InitOptions::plugins"));

  nlohmann::json report;
  report["scenario"] = out.string();
  report["name"] = name;
  report["frames"] = db.frameCount();
  report["seconds"] = db.frameCount() * db.frameTime;
  report["units"] = distinctUnits;
  report["root_motion_joint"] = db.rootMotion.jointName;
  report["root_motion"] = db.rootMotion.sentence;
  report["standing_height_m"] = {minHeight, maxHeight};
  report["effective_punches"] = strikes;
  report["effective_kicks"] = kicks;
  report["graph"] = {{"threshold", chosen->threshold},
                     {"contact_event", std::string(contactEventName(chosen->event))},
                     {"kept_share", chosen->share(db.frameCount())},
                     {"states", chosen->states},
                     {"actions", chosen->actions},
                     {"punches_in_actions", chosen->hits},
                     {"kicks_in_actions", chosen->kicks},
                     {"usable", chosen->usable(db)}};
  report["behaviors"] = kind == "punch"  ? nlohmann::json{"approach", "hit"}
                        : kind == "kick" ? nlohmann::json{"kick"}
                                         : nlohmann::json{"goal"};
  report["locomotion_share"] = std::round(1000 * travelling) / 1000;
  report["warnings"] = warnings;
  const std::string file = out.string();
  report["next"] = {fmt::format("mgrl graph {}", file), fmt::format("mgrl train {}", file),
                    fmt::format("mgrl eval {}", file), fmt::format("mgrl serve {}", file)};
  return report;
}

std::string initText(const nlohmann::json& r) {
  std::string out;
  out += fmt::format("wrote {} ({} frames, {:.1f} s, units {})\n", r["scenario"].get<std::string>(),
                     r["frames"].get<std::size_t>(), r["seconds"].get<double>(),
                     fmt::join(r["units"].get<std::vector<std::string>>(), ", "));
  out += fmt::format("  {}\n", r["root_motion"].get<std::string>());
  out += fmt::format("  standing height {:.2f} to {:.2f} m; {} effective punches, {} kicks\n",
                     r["standing_height_m"][0].get<double>(), r["standing_height_m"][1].get<double>(),
                     r["effective_punches"].get<std::size_t>(), r["effective_kicks"].get<std::size_t>());
  const nlohmann::json& g = r["graph"];
  out += fmt::format(
      "  graph: threshold {:g}, {}: {:.0f} % of frames kept, {} states, {} actions{}\n", g["threshold"].get<double>(),
      g["contact_event"].get<std::string>(), 100 * g["kept_share"].get<double>(), g["states"].get<std::size_t>(),
      g["actions"].get<std::size_t>(), g["usable"].get<bool>() ? "" : " (the best found; more capture would help)");
  out += fmt::format("  behaviours: {}\n", fmt::join(r["behaviors"].get<std::vector<std::string>>(), ", "));
  for (const auto& w : r["warnings"]) out += fmt::format("  warning: {}\n", w.get<std::string>());
  out += "next:\n";
  for (const auto& c : r["next"]) out += fmt::format("  {}\n", c.get<std::string>());
  return out;
}

}  // namespace mgrl
