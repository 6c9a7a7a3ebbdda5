#pragma once
/// \file
/// Builds the state-action model from a MotionDatabase (Lee & Lee 2004, sec. 3 and 6.3,
/// after Lee et al. 2002): transitions between similar frames at the same contact event,
/// the largest strongly connected component, then frames with several out-edges become
/// states and the paths between them actions.
#include <cstdint>
#include <string>

#include "mgrl/graph/frame_distance.hpp"
#include "mgrl/graph/graph_params.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/motion/motion_database.hpp"

namespace mgrl {

struct GraphBuildReport {
  TransitionSearchStats search;
  std::size_t transitionsFound = 0;  ///< candidates passing threshold, contact and local-minimum tests
  std::size_t components = 0;        ///< strongly connected components of the frame graph
  int outDegreeBound = 0;            ///< GraphParams::maxOutDegree as applied (0: none)
  std::size_t transitionsPruned = 0;    ///< inside the component, left out by the bound
  std::size_t transitionsRestored = 0;  ///< left out, then put back to keep the component whole
  std::size_t repairRounds = 0;
};

/// What a library's graph options did, in a sentence ("at most 32 actions a state: ...;
/// 330 cut points where the performer stands still"), or "" when neither was on.
std::string librarySentence(const GraphBuildReport& report);

/// Builds the model. Throws mgrl::Error when the largest component has fewer than
/// params.minStates states, with the numbers and the parameters to relax.
StateActionModel buildStateActionModel(const MotionDatabase& db, const GraphParams& params,
                                       GraphBuildReport* report = nullptr);

/// The avatar frame of global frame `frame` (from the clip's annotation).
const AvatarFrame& avatarFrameAt(const MotionDatabase& db, std::uint32_t frame);

/// Ground motion from the avatar frame at `from` to the one at `to`, in the frame of `from`.
GroundMotion relativeMotion(const AvatarFrame& from, const AvatarFrame& to);
/// a then b (b expressed in a's end frame).
GroundMotion compose(const GroundMotion& a, const GroundMotion& b);
/// A point given in the avatar frame that `motion` leads to, in the frame `motion` starts
/// from (height unchanged). With `motion` a world placement: avatar frame to world.
Eigen::Vector3d transformPoint(const GroundMotion& motion, const Eigen::Vector3d& point);

}  // namespace mgrl
