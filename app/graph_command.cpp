#include "graph_command.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "plural.hpp"

namespace mgrl::app {

namespace {

double round3(double v) { return std::round(v * 1000) / 1000; }

nlohmann::json travelJson(const CaptureTravel& t) {
  nlohmann::json reaches = nlohmann::json::object();
  for (const auto& r : t.reaches) reaches[r.behavior] = round3(r.reach_m);
  return {{"clip_travel_m", round3(t.clipTravel_m)},
          {"clip", t.clip},
          {"root_extent_m", round3(t.rootExtent_m)},
          {"action_travel_m", round3(t.actionTravel_m)},
          {"walk_travel_m", round3(t.walkTravel_m)},
          {"walk_seconds", kTravelWalkSeconds},
          {"grid_reach_m", reaches},
          {"warnings", t.warnings}};
}

// Each clip's share of frames in the component, in file order.
nlohmann::json clipShares(const GraphResult& g) {
  const StateActionModel& m = g.model;
  const std::vector<std::size_t> inside = componentFramesByClip(m, g.db.clips.size());
  nlohmann::json list = nlohmann::json::array();
  for (std::size_t k = 0; k < inside.size(); ++k) {
    const std::uint32_t frames = m.clipOffset[k + 1] - m.clipOffset[k];
    list.push_back({{"clip", g.db.clips[k].name},
                    {"frames", frames},
                    {"in_scc", round3(static_cast<double>(inside[k]) / std::max<std::uint32_t>(1, frames))}});
  }
  return list;
}

}  // namespace

nlohmann::json graphJson(const GraphResult& g) {
  const StateActionModel& m = g.model;
  const ActionFrameStats l = actionFrameStats(m);
  return {{"frames_total", m.framesTotal},
          {"frames_in_scc", m.componentFrames.size()},
          {"scc_fraction", round3(m.framesTotal ? static_cast<double>(m.componentFrames.size()) / m.framesTotal : 0)},
          {"clips", clipShares(g)},
          {"transitions", m.transitionDistance.size()},
          {"library", librarySentence(g.report).empty()
                          ? nlohmann::json()
                          : nlohmann::json{{"max_out_degree", g.report.outDegreeBound},
                                           {"transitions_pruned", g.report.transitionsPruned},
                                           {"transitions_restored", g.report.transitionsRestored},
                                           {"standing_cut_frames", g.report.search.standingCutFrames}}},
          {"states", m.stateCount()},
          {"actions", m.actionCount()},
          {"mean_action_frames", round3(l.mean)},
          {"min_action_frames", l.min},
          {"max_action_frames", l.max},
          {"effective_hits", g.db.hitCount()},
          {"action_hits", m.hits.size()},
          {"effective_kicks", g.db.kickCount()},
          {"action_kicks", m.kicks.size()},
          {"fps", round3(1.0 / m.frameTime)},
          {"build_seconds", round3(g.buildSeconds)},
          {"playback",
           {{"frames", g.playback.frames},
            {"transitions", g.playback.transitions},
            {"foot_slide_mps", round3(g.playback.slide.meanSpeed_mps)},
            {"source_foot_slide_mps", round3(g.playback.sourceSlideSameFrames_mps)},
            {"capture_foot_slide_mps", round3(g.playback.captureSlide.meanSpeed_mps)},
            {"max_joint_step_m", round3(g.playback.maxJointStep_m)},
            {"source_max_joint_step_m", round3(g.playback.sourceMaxJointStep_m)},
            {"worst_joint_step_ratio", round3(g.playback.worstJointStepRatio)}}},
          {"travel", travelJson(g.travel)},
          {"root_motion_joint", g.db.clips.empty() ? nlohmann::json() : nlohmann::json(g.db.rootMotion.jointName)},
          {"punch_min_speed_auto_mps",
           g.db.autoPunchSpeed ? nlohmann::json(round3(g.db.autoPunchSpeed->speed_mps)) : nlohmann::json()},
          {"seconds", round3(g.seconds)},
          {"cached", g.fromCache},
          {"cache", g.bundle.string()}};
}

std::string graphText(const GraphResult& g) {
  const StateActionModel& m = g.model;
  const ActionFrameStats l = actionFrameStats(m);
  std::string out;
  out += fmt::format("frames          {} in {} at {:g} fps ({:.1f} s)\n", m.framesTotal,
                     counted(g.db.clips.size(), "file"), 1.0 / m.frameTime, m.framesTotal * m.frameTime);
  if (g.db.rootMotion.joint != 0) out += fmt::format("root motion     {}\n", g.db.rootMotion.sentence);
  if (g.db.autoPunchSpeed) out += fmt::format("punches         {}\n", g.db.autoPunchSpeed->sentence());
  out += fmt::format("component       {} frames ({:.1f} % of the data)\n", m.componentFrames.size(),
                     m.framesTotal ? 100.0 * static_cast<double>(m.componentFrames.size()) / m.framesTotal : 0.0);
  out += fmt::format("transitions     {}\n", m.transitionDistance.size());
  if (const std::string library = librarySentence(g.report); !library.empty())
    out += fmt::format("library         {}\n", library);
  out += fmt::format("states          {}\n", m.stateCount());
  out += fmt::format("actions         {} ({:.1f} per state)\n", m.actionCount(),
                     m.stateCount() ? static_cast<double>(m.actionCount()) / m.stateCount() : 0.0);
  out += fmt::format("action frames   min {}, mean {:.1f}, max {} ({:.2f} s mean)\n", l.min, l.mean, l.max,
                     l.mean * m.frameTime);
  out += fmt::format("effective hits  {} in the data, {} inside actions\n", g.db.hitCount(), m.hits.size());
  if (g.db.kickCount() > 0)
    out += fmt::format("effective kicks {} in the data, {} inside actions\n", g.db.kickCount(), m.kicks.size());
  const CaptureTravel& t = g.travel;
  std::string reaches;
  for (const auto& r : t.reaches)
    reaches += fmt::format("{}{} {:.2f} m", reaches.empty() ? "; grids reach " : ", ", r.behavior, r.reach_m);
  out += fmt::format(
      "travel          root up to {:.2f} m from a clip's start ({}), clip extent up to {:.2f} m, "
      "largest action {:.2f} m, {:g} s graph walk {:.2f} m{}\n",
      t.clipTravel_m, t.clip.empty() ? "-" : t.clip, t.rootExtent_m, t.actionTravel_m, kTravelWalkSeconds,
      t.walkTravel_m, reaches);
  out += fmt::format(
      "playback check  {} frames, {} transitions blended over {} frames: foot sliding {:.3f} m/s "
      "(same frames in the capture: {:.3f}), largest joint step {:.3f} m (capture: {:.3f})\n",
      g.playback.frames, g.playback.transitions, g.blendFrames, g.playback.slide.meanSpeed_mps,
      g.playback.sourceSlideSameFrames_mps, g.playback.maxJointStep_m, g.playback.sourceMaxJointStep_m);
  out += fmt::format("build           {:.3f} s{}\n", g.buildSeconds,
                     g.fromCache ? fmt::format(" (reused from {})", g.bundle.string()) : std::string());
  return out;
}

}  // namespace mgrl::app
