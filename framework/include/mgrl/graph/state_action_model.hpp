#pragma once
/// \file
/// The state-action model every learner, controller and view shares (Lee & Lee 2004,
/// sec. 3 and 6.3, after Lee et al. 2002): states are motion-graph frames with two or more
/// out-edges, actions the frame paths from one state to the next. Plain arrays, immutable
/// once built, so they can be cached as .npy files and swept by learners without
/// indirection.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mgrl {

/// A 2-D rigid motion on the ground plane in an avatar frame (DESIGN.md sec. 3): move by
/// (dx, dz) metres, then turn by dyaw radians about +Y (counter-clockwise seen from above,
/// i.e. from +Z towards +X).
struct GroundMotion {
  double dx = 0, dz = 0, dyaw = 0;
};

/// One effective hitting point inside an action (paper sec. 6.2): a punch's fist tip, or
/// a kick's toe tip (StateActionModel::kicks).
struct ActionHit {
  std::uint32_t action = 0;
  std::uint32_t offset = 0;   ///< frames after the decision (1 = the action's first frame)
  std::uint8_t hand = 0;      ///< 0 left, 1 right (the foot, for a kick)
  float x = 0, y = 0, z = 0;  ///< fist (toe) tip in the avatar frame of the decision (m)
  float weight = 0;           ///< speed / fastest effective hit (kick) in the data, in (0, 1]
};

/// Everything the graph builder produces. Frame indices are global: clip c's frame f is
/// clipOffset[c] + f in the concatenation of the scenario's clips (after resampling).
struct StateActionModel {
  double frameTime = 0;  ///< seconds per frame (1 / scenario fps)
  std::uint32_t framesTotal = 0;
  /// Start of each clip in the global frame numbering; clipOffset.back() == framesTotal.
  std::vector<std::uint32_t> clipOffset;

  /// Frames of the largest strongly connected component, ascending.
  std::vector<std::uint32_t> componentFrames;
  /// Transition edges i -> j kept in the component (besides the clips' own i -> i + 1),
  /// as pairs (i, j), sorted; and the frame distance behind each.
  std::vector<std::uint32_t> transitions;  // 2 per edge
  std::vector<float> transitionDistance;

  /// The frame of each state, ascending.
  std::vector<std::uint32_t> stateFrame;

  /// Per action (index a): the state it leaves and the state it ends at (state indices),
  /// its frames in actionFrames[actionFrameBegin[a], actionFrameBegin[a + 1]) (the frames played after the decision;
  /// the last is the end state's frame), and its root displacement from the decision to
  /// its last frame in the avatar frame of the decision.
  std::vector<std::uint32_t> actionFrom, actionTo;
  std::vector<std::uint32_t> actionFrameBegin;  ///< actionCount() + 1 entries
  std::vector<double> actionDisplacement;       ///< (dx, dz, dyaw) per action
  /// Actions are sorted by the state they leave: state s's are [stateActionBegin[s],
  /// stateActionBegin[s + 1]).
  std::vector<std::uint32_t> stateActionBegin;  ///< stateCount() + 1 entries

  /// Per action frame (same indexing as actionFrames): the source frame played, the avatar
  /// frame there relative to the decision's (x, z, yaw), and the centroid of all effective
  /// hitting points carried along with the avatar (x, y, z), in the decision's avatar frame.
  std::vector<std::uint32_t> actionFrames;
  std::vector<double> frameRoot;     ///< 3 per action frame
  std::vector<float> frameCentroid;  ///< 3 per action frame
  /// 1 where the played frame enters through a transition edge (blending starts there).
  std::vector<std::uint8_t> frameEntersTransition;

  /// Effective hits inside actions, sorted by (action, offset, hand).
  std::vector<ActionHit> hits;
  std::vector<std::uint32_t> actionHitBegin;  ///< actionCount() + 1 entries
  /// Effective kicks inside actions (Annotation::kicks), the same way: hand is the foot.
  std::vector<ActionHit> kicks;
  std::vector<std::uint32_t> actionKickBegin;  ///< actionCount() + 1 entries

  /// The centroid of all effective hitting points in the avatar frame (m), and the fastest
  /// effective hit's speed (m/s, 0 if there is none).
  double centroid[3] = {0, 0, 0};
  double maxHitSpeed_mps = 0;
  /// The fastest effective kick's toe speed (m/s, 0 if there is none).
  double maxKickSpeed_mps = 0;

  /// The skeleton's joints, for reward terms and success criteria that measure a joint
  /// (scenarios/README.md, body points): their names (J of them; none in models made by
  /// hand), each role's joint in roleNames() order (-1 if the role has none; empty when J
  /// is 0), and per source frame f and joint j, at [f * J + j]: the joint's position in
  /// that frame's own avatar frame (3 floats, m; carried to a decision's frame by
  /// frameRoot) and its speed in the capture (m/s, central differences within its clip).
  std::vector<std::string> jointNames;
  std::vector<std::int32_t> roleJoint;
  std::vector<float> sourceJoint;       ///< 3 per (source frame, joint)
  std::vector<float> sourceJointSpeed;  ///< 1 per (source frame, joint)

  std::size_t stateCount() const { return stateFrame.size(); }
  std::size_t actionCount() const { return actionFrom.size(); }
  std::size_t actionLength(std::size_t a) const { return actionFrameBegin[a + 1] - actionFrameBegin[a]; }
  std::span<const std::uint32_t> framesOf(std::size_t a) const {
    return {actionFrames.data() + actionFrameBegin[a], actionLength(a)};
  }
  std::span<const ActionHit> hitsOf(std::size_t a) const {
    return {hits.data() + actionHitBegin[a], actionHitBegin[a + 1] - actionHitBegin[a]};
  }
  std::span<const ActionHit> kicksOf(std::size_t a) const {
    return {kicks.data() + actionKickBegin[a], actionKickBegin[a + 1] - actionKickBegin[a]};
  }
  GroundMotion displacement(std::size_t a) const {
    return {actionDisplacement[3 * a], actionDisplacement[3 * a + 1], actionDisplacement[3 * a + 2]};
  }
};

/// How long the model's actions are, in frames (all 0 for a model without actions).
struct ActionFrameStats {
  std::size_t min = 0, max = 0;
  double mean = 0;
};
ActionFrameStats actionFrameStats(const StateActionModel& m);

/// How many of each clip's frames are in the component, in clip order (empty when
/// clipOffset does not hold `clips` clips).
std::vector<std::size_t> componentFramesByClip(const StateActionModel& m, std::size_t clips);

/// Checks every structural invariant of `m` that code indexing its arrays relies on:
/// array sizes agree with each other; offset arrays (clipOffset, actionFrameBegin,
/// stateActionBegin, actionHitBegin) start at 0, do not decrease and end at the size of
/// what they index; every action has a frame; frame and state indices are in range;
/// actions are grouped by the state they leave and end on their end state's frame;
/// componentFrames and stateFrame strictly ascend; transitions are sorted pairs; hits
/// belong to their action, sorted by (offset, hand), 1 <= offset <= action length, hand 0
/// or 1, weight in (0, 1]; frameTime > 0; every floating-point value finite; the joint
/// arrays sized by framesTotal and jointNames, role joints in [-1, J), speeds at least 0.
/// Throws mgrl::Error with a message starting with `source` and naming the field and index,
/// e.g. `graph: actionFrames[7]: expected a frame below framesTotal 40, found 40`.
void checkModel(const StateActionModel& m, std::string_view source);

}  // namespace mgrl
