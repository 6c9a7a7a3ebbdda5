// Where a session's graph comes from (DESIGN.md sec. 2): the scenario's capture, parsed and
// built into the motion graph and state-action model (paper sec. 3, 6.3), or the cache's
// bundle of it; and how far that capture carries the avatar.
#include "mgrl/session/graph_source.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <optional>

#include <fmt/format.h>

#include "mgrl/core/hash.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/graph/graph_cache.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/graph/playback.hpp"

namespace mgrl {

namespace {

nlohmann::json paramsJson(const Scenario& s) {
  const GraphParams& g = s.graph;
  nlohmann::json weights = nlohmann::json::object();
  for (const auto& [joint, w] : g.jointWeights) weights[joint] = w;
  nlohmann::json files = nlohmann::json::array();
  for (const auto& f : s.motion.files) files.push_back(f.filename().string());
  return {{"files", files},
          {"fps", s.motion.fps},
          {"threshold", g.threshold},
          {"velocity_weight", g.velocityWeight},
          {"root_height_weight", g.rootHeightWeight},
          {"contact_event", std::string(contactEventName(g.contactEvent))},
          {"local_minimum", g.localMinimum},
          {"blend_frames", g.blendFrames},
          {"min_states", g.minStates},
          {"joint_weights", weights}};
}

}  // namespace

namespace {

// The clips' part of CaptureTravel: how far each clip carries the root.
CaptureTravel clipTravel(const MotionDatabase& db) {
  CaptureTravel t;
  for (const Clip& clip : db.clips) {
    const auto& frames = clip.annotation.frames;
    if (frames.empty()) continue;
    const Eigen::Vector3d start = frames.front().origin;
    Eigen::Vector2d lo(start.x(), start.z()), hi = lo;
    for (const AvatarFrame& f : frames) {
      const Eigen::Vector2d p(f.origin.x(), f.origin.z());
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      const double d = std::hypot(f.origin.x() - start.x(), f.origin.z() - start.z());
      if (d > t.clipTravel_m) {
        t.clipTravel_m = d;
        t.clip = clip.name;
      }
    }
    t.rootExtent_m = std::max(t.rootExtent_m, (hi - lo).norm());
  }
  return t;
}

nlohmann::json clipTravelJson(const CaptureTravel& t) {
  return {{"clip_travel_m", t.clipTravel_m}, {"clip", t.clip},           {"root_extent_m", t.rootExtent_m},
          {"action_travel_m", t.actionTravel_m}, {"walk_travel_m", t.walkTravel_m}};
}

// The clips' part kept in a graph bundle's provenance; nullopt if absent or malformed (a
// bundle from before it was kept: the capture is parsed instead).
std::optional<CaptureTravel> clipTravelFrom(const nlohmann::json& manifest) {
  if (!manifest.is_object() || !manifest.contains("provenance") || !manifest["provenance"].is_object()) return std::nullopt;
  const nlohmann::json& p = manifest["provenance"];
  if (!p.contains("capture_travel") || !p["capture_travel"].is_object()) return std::nullopt;
  const nlohmann::json& c = p["capture_travel"];
  if (!c.contains("clip_travel_m") || !c["clip_travel_m"].is_number() || !c.contains("root_extent_m") ||
      !c["root_extent_m"].is_number() || !c.contains("clip") || !c["clip"].is_string())
    return std::nullopt;
  CaptureTravel t;
  t.clipTravel_m = c["clip_travel_m"].get<double>();
  t.rootExtent_m = c["root_extent_m"].get<double>();
  t.clip = c["clip"].get<std::string>();
  if (!std::isfinite(t.clipTravel_m) || !std::isfinite(t.rootExtent_m)) return std::nullopt;
  // The graph walk's part, kept since version 4 (the model's own, so a cached graph need
  // not walk again: a few milliseconds of every command's start).
  if (c.contains("action_travel_m") && c["action_travel_m"].is_number() && c.contains("walk_travel_m") &&
      c["walk_travel_m"].is_number()) {
    t.actionTravel_m = c["action_travel_m"].get<double>();
    t.walkTravel_m = c["walk_travel_m"].get<double>();
    t.walked = std::isfinite(t.actionTravel_m) && std::isfinite(t.walkTravel_m);
  }
  return t;
}

// What a library's graph options did (GraphBuildReport), kept in a graph bundle's
// provenance when either was on, so that a reused graph reports it too.
nlohmann::json libraryJson(const GraphBuildReport& r) {
  if (r.outDegreeBound == 0 && r.search.standingCutFrames == 0) return nullptr;
  return {{"max_out_degree", r.outDegreeBound},
          {"transitions_pruned", r.transitionsPruned},
          {"transitions_restored", r.transitionsRestored},
          {"repair_rounds", r.repairRounds},
          {"standing_cut_frames", r.search.standingCutFrames}};
}

// The same read back; left at zeros when absent or not five whole numbers >= 0 (a bundle
// from before it was kept, or without the options).
void libraryFrom(const nlohmann::json& manifest, GraphBuildReport& r) {
  const nlohmann::json* library = nullptr;
  if (manifest.is_object() && manifest.contains("provenance") && manifest["provenance"].is_object() &&
      manifest["provenance"].contains("library"))
    library = &manifest["provenance"]["library"];
  if (!library || !library->is_object()) return;
  const char* keys[] = {"max_out_degree", "transitions_pruned", "transitions_restored", "repair_rounds",
                        "standing_cut_frames"};
  for (const char* key : keys)
    if (!library->contains(key) || !(*library)[key].is_number_unsigned()) return;
  if ((*library)["max_out_degree"].get<std::uint64_t>() > 1'000'000) return;
  r.outDegreeBound = (*library)["max_out_degree"].get<int>();
  r.transitionsPruned = (*library)["transitions_pruned"].get<std::size_t>();
  r.transitionsRestored = (*library)["transitions_restored"].get<std::size_t>();
  r.repairRounds = (*library)["repair_rounds"].get<std::size_t>();
  r.search.standingCutFrames = (*library)["standing_cut_frames"].get<std::size_t>();
}

// True if a bundle's clips are the scenario's files, in order: always so for a bundle
// whose key matched, unless it was saved without them (then the capture is parsed).
bool bundledMotionFits(const std::vector<std::pair<std::string, Motion>>& motions, const MotionSpec& spec) {
  if (motions.empty() || motions.size() != spec.files.size()) return false;
  for (std::size_t c = 0; c < motions.size(); ++c)
    if (motions[c].first != spec.files[c].filename().string()) return false;
  return true;
}

}  // namespace

CaptureTravel measureTravel(const Scenario& scenario, const MotionDatabase& db, const StateActionModel& model,
                            const Plugins& plugins) {
  return measureTravel(scenario, clipTravel(db), model, plugins);
}

CaptureTravel walkTravel(CaptureTravel clips, const StateActionModel& model) {
  CaptureTravel t = std::move(clips);
  t.actionTravel_m = t.walkTravel_m = 0;
  for (std::size_t a = 0; a < model.actionCount(); ++a)
    t.actionTravel_m = std::max(t.actionTravel_m, std::hypot(model.actionDisplacement[3 * a], model.actionDisplacement[3 * a + 1]));
  // Chained actions carry the avatar farther than one clip: from every state, walk the
  // graph greedily away from the start for kTravelWalkSeconds. A lower bound on what a
  // policy can do, but one that shows whether the capture goes anywhere at all.
  const double walkFrames = kTravelWalkSeconds / model.frameTime;
  for (std::size_t start = 0; start < model.stateCount(); ++start) {
    GroundMotion total;
    double frames = 0;
    std::size_t state = start;
    while (frames < walkFrames) {
      const std::uint32_t begin = model.stateActionBegin[state], end = model.stateActionBegin[state + 1];
      if (begin == end) break;
      std::uint32_t best = begin;
      GroundMotion bestTotal;
      double bestDistance = -1;
      for (std::uint32_t a = begin; a < end; ++a) {
        const GroundMotion next = compose(total, {model.actionDisplacement[3 * a], model.actionDisplacement[3 * a + 1],
                                                  model.actionDisplacement[3 * a + 2]});
        const double d = std::hypot(next.dx, next.dz);
        if (d > bestDistance) {
          bestDistance = d;
          best = a;
          bestTotal = next;
        }
      }
      total = bestTotal;
      frames += static_cast<double>(model.actionLength(best));
      state = model.actionTo[best];
      t.walkTravel_m = std::max(t.walkTravel_m, bestDistance);
    }
  }
  t.walked = true;
  return t;
}

CaptureTravel measureTravel(const Scenario& scenario, CaptureTravel clips, const StateActionModel& model,
                            const Plugins& plugins) {
  CaptureTravel t = clips.walked ? std::move(clips) : walkTravel(std::move(clips), model);
  const double travel = std::max(t.clipTravel_m, t.walkTravel_m);
  for (const BehaviorSpec& spec : scenario.behaviors) {
    std::unique_ptr<Discretizer> grid;
    try {
      grid = plugins.discretizers.create(spec.discretizer, model);
    } catch (const Error&) {
      continue;  // a bad block is train's to report, with its line
    }
    double reach = 0;
    for (std::size_t v = 0; v < grid->vertexCount(); ++v) {
      const Eigen::Vector3d p = grid->vertexPosition(v);
      reach = std::max(reach, std::hypot(p.x(), p.z()));
    }
    t.reaches.push_back({spec.name, reach});
    if (reach > kTravelReachFactor * travel)
      t.warnings.push_back(fmt::format(
          "behaviors.{}: its grid reaches {:.2f} m from the avatar, but the capture carries the root at most {:.2f} m "
          "from a clip's start and a {:g} s walk through the graph {:.2f} m (largest action: {:.2f} m): targets that "
          "far may be out of reach whatever is learned; add capture that travels, or shrink the grid",
          spec.name, reach, t.clipTravel_m, kTravelWalkSeconds, t.walkTravel_m, t.actionTravel_m));
  }
  return t;
}

std::filesystem::path defaultCacheDirectory() {
  if (const char* env = std::getenv("MGRL_CACHE"); env && *env) return env;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "mgrl";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "mgrl";
  return ".mgrl-cache";
}

const Plugins& requirePlugins(const Plugins* plugins, std::string_view where) {
  if (!plugins)
    throw Error(
        fmt::format("{}: expected the plug-ins to build behaviours with (mgrl::builtinPlugins() for the "
                    "built-in ones), found none",
                    where));
  return *plugins;
}

GraphResult obtainGraph(const Scenario& scenario, const GraphOptions& options) {
  const Plugins& plugins = requirePlugins(options.plugins, "GraphOptions::plugins");
  const auto start = std::chrono::steady_clock::now();
  auto log = [&](const std::string& message) {
    if (options.log) options.log(message);
  };
  GraphResult result;
  // Loader warnings are warnings; the log also carries plain progress.
  WarningSink warn;
  if (options.log) warn = [&](const std::string& message) { log(fmt::format("warning: {}", message)); };
  result.key = options.key.empty() ? graphCacheKey(scenario) : options.key;
  const std::filesystem::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  // One bundle per scenario file: a changed scenario replaces its bundle instead of piling up.
  std::error_code ec;
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(scenario.path, ec);
  result.bundle = cacheDir / "graphs" /
                  fmt::format("{}-{}", scenario.name, hexDigest(hashBytes(canonical.string())).substr(0, 8));

  if (!options.noCache) {
    GraphBundleLoad cached = loadGraphBundle(result.bundle, result.key, options.motion);
    if (cached.status == GraphBundleLoad::Ok) {
      result.model = std::move(cached.model);
      result.fromCache = true;
      result.buildSeconds = cached.manifest["provenance"].value("build_seconds", 0.0);
      libraryFrom(cached.manifest, result.report);
      log(fmt::format("graph: reused {}", result.bundle.string()));
      // The key covers the capture's bytes, so what was measured on it when the bundle was
      // made still holds; parse it only where poses are wanted.
      const std::optional<CaptureTravel> clips = clipTravelFrom(cached.manifest);
      if (options.motion && bundledMotionFits(cached.motions, scenario.motion)) {
        // The capture as it was parsed when the bundle was made (the key covers its bytes);
        // annotated again here, as loadMotionDatabase() would.
        result.db = makeMotionDatabase(std::move(cached.motions), scenario.motion, warn);
      } else if (options.motion || !clips) {
        result.db = loadMotionDatabase(scenario.motion, warn);
      }
      result.travel = clips ? measureTravel(scenario, *clips, result.model, plugins)
                            : measureTravel(scenario, result.db, result.model, plugins);
      result.seconds = since(start);
      for (const std::string& w : result.travel.warnings) log(fmt::format("graph: warning: {}", w));
      return result;
    }
    if (cached.status == GraphBundleLoad::Stale) log(fmt::format("graph: cache is stale, rebuilding ({})", cached.reason));
    if (cached.status == GraphBundleLoad::Damaged)
      log(fmt::format("graph: cache is damaged, rebuilding ({})", cached.reason));
  }
  result.db = loadMotionDatabase(scenario.motion, warn);
  log(fmt::format("graph: building from {} frames in {}", result.db.frameCount(), fmt::format("{} file{}", result.db.clips.size(), result.db.clips.size() == 1 ? "" : "s")));
  const auto buildStart = std::chrono::steady_clock::now();
  result.model = buildStateActionModel(result.db, scenario.graph, &result.report);
  result.buildSeconds = since(buildStart);

  const CaptureTravel clips = walkTravel(clipTravel(result.db), result.model);
  nlohmann::json provenance = {{"key", result.key},
                               {"scenario", scenario.name},
                               {"scenario_path", canonical.string()},
                               {"tool_version", std::string(kVersion)},
                               {"build_seconds", result.buildSeconds},
                               {"parameters", paramsJson(scenario)},
                               {"frames_total", result.model.framesTotal},
                               {"frames_in_scc", result.model.componentFrames.size()},
                               {"states", result.model.stateCount()},
                               {"actions", result.model.actionCount()},
                               {"capture_travel", clipTravelJson(clips)}};
  if (nlohmann::json library = libraryJson(result.report); !library.is_null())
    provenance["library"] = std::move(library);
  try {
    std::filesystem::create_directories(result.bundle.parent_path());
    saveGraphBundle(result.bundle, result.model, provenance, result.db.clips);
    log(fmt::format("graph: saved {}", result.bundle.string()));
  } catch (const std::exception& e) {
    // The graph is good; only reuse is lost. Say so and go on.
    log(fmt::format("graph: warning: could not write the cache ({})", e.what()));
  }
  result.travel = measureTravel(scenario, clips, result.model, plugins);
  for (const std::string& w : result.travel.warnings) log(fmt::format("graph: warning: {}", w));
  result.seconds = since(start);
  return result;
}

void measurePlayback(GraphResult& graph, int blendFrames) {
  graph.blendFrames = blendFrames;
  graph.playback = checkPlayback(graph.db, graph.model, blendFrames, kPlaybackCheckActions, kPlaybackCheckSeed);
}

}  // namespace mgrl
