#pragma once
/// \file
/// Where a session's graph comes from: the scenario's capture built into the motion graph
/// and state-action model (paper sec. 3, 6.3), or that graph reused from the cache; how far
/// the capture carries the avatar against how far the behaviours' grids reach.
#include <chrono>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/graph/playback.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/plugins.hpp"

namespace mgrl {

/// Seconds since `start` on the steady clock.
inline double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct GraphOptions {
  std::filesystem::path cacheDir;  ///< empty: defaultCacheDirectory()
  bool noCache = false;            ///< rebuild even when a matching bundle exists
  WarningSink log;                 ///< progress and cache messages (stderr)
  /// Parse the capture into GraphResult::db even when the graph comes from the cache: what
  /// posing avatars needs (simulate, the viewer, graph's report). Training and eval need
  /// only the model, and a cached graph then costs no parsing, so the command starts quickly.
  bool motion = true;
  /// The scenario's graphCacheKey() if the caller has it (it hashes every capture file:
  /// computed once per command); empty: computed here.
  std::string key;
  /// The discretizers the behaviours' grids come from (their reach is measured against the
  /// capture's travel). Required: SessionOptions::plugins, the built-in ones by default.
  const Plugins* plugins = nullptr;
};

/// `*plugins`; throws mgrl::Error naming `where` (the options that lack them) if null.
const Plugins& requirePlugins(const Plugins* plugins, std::string_view where);

/// How far the capture carries the avatar, against how far the behaviours' grids reach
/// (two standing clips cannot approach a target 2 m away, whatever is learned).
struct CaptureTravel {
  double clipTravel_m = 0;    ///< largest ground distance of the root from its clip's first frame
  std::string clip;           ///< the clip where it is reached
  double rootExtent_m = 0;    ///< largest diagonal of a clip's root positions' ground bounding box
  double actionTravel_m = 0;  ///< largest root ground displacement of one action
  /// Farthest a greedy walk through the graph (each decision the action ending farthest
  /// from the start) gets in kTravelWalkSeconds, over every starting state.
  double walkTravel_m = 0;
  /// True once actionTravel_m and walkTravel_m are measured (walkTravel()).
  bool walked = false;
  struct Reach {
    std::string behavior;
    double reach_m = 0;  ///< largest ground distance of its grid's vertices from the avatar
  };
  std::vector<Reach> reaches;  ///< per behaviour whose discretizer could be built
  /// Behaviours whose grid reaches more than kTravelReachFactor times the larger of
  /// clipTravel_m and walkTravel_m.
  std::vector<std::string> warnings;
};

/// A grid reaching this many times farther than the capture ever travels is warned about:
/// chaining actions carries the avatar farther than one clip, but not without limit.
inline constexpr double kTravelReachFactor = 2.0;
/// Seconds of motion the travel walk plays (eval's trials play 10).
inline constexpr double kTravelWalkSeconds = 10.0;

/// A built or cached graph with the capture it indexes.
struct GraphResult {
  /// The parsed capture; empty (no skeleton, no clips) when GraphOptions::motion was false
  /// and the graph came from the cache.
  MotionDatabase db;
  StateActionModel model;
  /// Zeros when loaded from the cache, but for what a library's options did (outDegreeBound,
  /// transitionsPruned, transitionsRestored, repairRounds, search.standingCutFrames), which
  /// the bundle keeps.
  GraphBuildReport report;
  bool fromCache = false;
  double buildSeconds = 0;  ///< of the build that made the model (the cached one's if reused)
  double seconds = 0;       ///< this call, loading included
  std::filesystem::path bundle;
  std::string key;
  /// Filled by obtainGraph(); its warnings also go to options.log.
  CaptureTravel travel;
  /// Filled by measurePlayback().
  PlaybackCheck playback;
  int blendFrames = 0;
};

/// The playback check `mgrl graph` reports: a seeded random walk of this many actions.
inline constexpr std::size_t kPlaybackCheckActions = 200;
inline constexpr std::uint64_t kPlaybackCheckSeed = 1;

/// Plays a seeded random walk through the graph with blending and measures foot sliding
/// and joint steps against the capture (see checkPlayback()).
void measurePlayback(GraphResult& graph, int blendFrames);

/// `--cache`, else MGRL_CACHE, else $XDG_CACHE_HOME/mgrl, else ~/.cache/mgrl, else ./.mgrl-cache.
std::filesystem::path defaultCacheDirectory();

/// How far the capture travels and how far each behaviour's grid reaches (behaviours whose
/// discretizer cannot be built are left out: training reports those).
CaptureTravel measureTravel(const Scenario& scenario, const MotionDatabase& db, const StateActionModel& model,
                            const Plugins& plugins);
/// The same from the clips' part (clipTravel_m, clip, rootExtent_m) measured before, as
/// the graph bundle keeps it, so that a cached graph needs no capture for it; the graph
/// walk's part too if `clips.walked` (else it is measured here by walkTravel()).
CaptureTravel measureTravel(const Scenario& scenario, CaptureTravel clips, const StateActionModel& model,
                            const Plugins& plugins);
/// `clips` with the model's part measured: actionTravel_m and walkTravel_m (walked = true).
CaptureTravel walkTravel(CaptureTravel clips, const StateActionModel& model);

/// Loads the scenario's capture and returns its graph: from the cache bundle when its key
/// matches, else built and saved there atomically. A stale or damaged bundle is reported
/// through options.log and rebuilt, never trusted. Also measures the capture's travel and
/// logs a warning for each behaviour whose grid reaches beyond it. Throws mgrl::Error on
/// bad input.
GraphResult obtainGraph(const Scenario& scenario, const GraphOptions& options);

}  // namespace mgrl
