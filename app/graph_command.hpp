#pragma once
/// \file
/// `mgrl graph SCENARIO`: builds (or reuses from the cache) a scenario's motion graph and
/// state-action model, and reports its size.
#include <chrono>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "mgrl/error.hpp"
#include "mgrl/motion_database.hpp"
#include "mgrl/motion_graph.hpp"
#include "mgrl/playback.hpp"
#include "mgrl/scenario.hpp"
#include "mgrl/state_action_model.hpp"

namespace mgrl::app {

/// Seconds since `start` on the steady clock.
inline double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct GraphOptions {
  std::filesystem::path cacheDir;  ///< empty: defaultCacheDirectory()
  bool noCache = false;            ///< rebuild even when a matching bundle exists
  WarningSink log;                 ///< progress and cache messages (stderr)
};

/// A built or cached graph with the capture it indexes.
struct GraphResult {
  MotionDatabase db;
  StateActionModel model;
  GraphBuildReport report;     ///< zeros when loaded from the cache
  bool fromCache = false;
  double buildSeconds = 0;     ///< of the build that made the model (the cached one's if reused)
  double seconds = 0;          ///< this call, loading included
  std::filesystem::path bundle;
  std::string key;
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

/// Loads the scenario's capture and returns its graph: from the cache bundle when its key
/// matches, else built and saved there atomically. A stale or damaged bundle is reported
/// through options.log and rebuilt, never trusted. Throws mgrl::Error on bad input.
GraphResult obtainGraph(const Scenario& scenario, const GraphOptions& options);

nlohmann::json graphJson(const GraphResult& graph);
std::string graphText(const GraphResult& graph);

}  // namespace mgrl::app
