#pragma once
/// \file
/// A world run headless on an open session (DESIGN.md sec. 5; paper sec. 5, 6.6, 6.7):
/// avatars in sparring pairs or with targets, played by the trained policy (or the online
/// search, or at random), collisions at effective punches, reactions; the report of speed
/// and hits, and the exports (mgrl/session/exports.hpp). `mgrl simulate` and Python's
/// Session.simulate call it; messages name the settings as the caller calls them
/// (SimulateFields: the command line's options, or Python's keywords).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/session/controllers.hpp"
#include "mgrl/session/exports.hpp"
#include "mgrl/session/session.hpp"

namespace mgrl {

/// What messages call the settings: the command line's options by default.
struct SimulateFields {
  ControllerFields controller;
  ExportFields exports;
  std::string_view avatars = "--avatars", seconds = "--seconds", topK = "--top-k", threads = "--threads";
  std::string_view poses = "--poses", policy = "--policy", partnerPolicy = "--partner-policy",
                   partnerPolicyUsage = "--partner-policy DIR", partnerRound = "--partner-round", round = "--round";
  /// The names Python's Session.simulate gives its keywords (avatars, seconds, bvh_out, ...),
  /// and would give the settings it does not take yet (top_k, threads, partner_policy, ...).
  static SimulateFields keywords();
};

struct SimulateSettings {
  ControllerChoice controller;
  long long avatars = 2;
  double seconds = 10;  ///< simulated time
  std::uint64_t seed = 1;
  long long topK = 0;  ///< > 0 overrides world.top_k for this run
  /// A second bundle the second avatar of each sparring pair plays ("" none: all play the policy).
  std::filesystem::path partnerPolicy;
  int partnerRound = 0;  ///< > 0: the partner plays that self-play round's tables
  int round = 0;         ///< > 0: the policy's avatars play that self-play round's tables (not the final ones)
  std::filesystem::path bvhOut, gltfOut, eventsOut;  ///< exports ("" none)
  bool poses = false;    ///< forward kinematics of every joint each frame (exports imply it)
  unsigned threads = 0;  ///< 0: the hardware's
  WarningSink log;       ///< progress of long runs (every 5 s); null: none
  /// Called once the world is set up, before it runs; its value is reported as
  /// "startup_seconds" (the command line's: seconds since the program started). Null: not reported.
  std::function<double()> startup;
  SimulateFields fields;  ///< what messages call the settings

  bool records() const { return !bvhOut.empty() || !gltfOut.empty(); }
  ExportRequest exportRequest() const {
    return {bvhOut, gltfOut, eventsOut, avatars, seconds, controller.name, seed, fields.exports};
  }
};

/// Every mistake in the settings, found before anything is loaded: mgrl::Error naming the
/// setting as settings.fields calls it. `controllers`: those the session will be opened
/// with (SessionOptions::plugins).
void checkSimulateSettings(const ControllerRegistry& controllers, const SimulateSettings& settings);

/// Runs the world on `session` and writes the exports prepared in `outputs`
/// (prepareOutputs(settings.exportRequest(), ...), made before the graph so that a bad
/// output place fails first); returns {"avatars", "frames", "avatar_frames_per_second",
/// "hits", "hits_per_avatar_minute", "hits_by_part", ...} (docs in README.md).
/// The session must hold the capture (SessionNeeds::motion, the default): poses, bodies and
/// exports need it.
/// `policy`: the tables the policy controllers play instead of the session's bundle (null:
/// the bundle); the report then names no policy folder.
nlohmann::json simulate(const Session& session, const SimulateSettings& settings, Outputs& outputs,
                        const std::vector<PolicyPart>* policy = nullptr);

}  // namespace mgrl
