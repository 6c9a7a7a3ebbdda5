#pragma once
/// \file
/// Frame-to-frame distance and transition candidates for the motion graph (Lee & Lee 2004,
/// sec. 6.3, after Lee et al. 2002, sec. 3.1): weighted geodesic joint-angle differences
/// plus weighted joint angular-velocity differences, with the root's yaw and ground
/// position factored out.
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "mgrl/graph/graph_params.hpp"
#include "mgrl/motion/motion_database.hpp"

namespace mgrl {

/// Per-frame features of a MotionDatabase, laid out for the distance kernels.
struct FrameFeatures {
  std::size_t frames = 0;
  /// Joints with a non-zero weight; slot 0 is the root's tilt (its rotation with the
  /// facing yaw removed), the others are local joint rotations.
  std::vector<int> joints;
  std::vector<float> weight;  ///< per slot, normalised to sum 1
  /// Unit quaternions per slot, structure of arrays: quat[(slot * 4 + component) * frames + frame].
  std::vector<float> quat;
  /// Euclidean features whose squared difference is the velocity and height term:
  /// frames x dims, row-major.
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> linear;
  std::vector<float> linearNorm2;  ///< squared norm of each row of `linear`
};

/// Computes the features. Throws mgrl::Error if graph.joint_weights names a joint the
/// skeleton does not have (listing its joints) or every weight is zero.
FrameFeatures computeFrameFeatures(const MotionDatabase& db, const GraphParams& params);

/// Squared distance between frames a and b, computed plainly in double precision with an
/// exact arccos (the reference the fast kernels are tested against).
double frameDistance2(const FrameFeatures& features, std::uint32_t a, std::uint32_t b);

/// Contact event class of every frame: -1 where none, else a small class id; transitions
/// join only frames of the same class. With ContactEvent::None every frame has class 0.
/// The last frame of a clip never has an event (nothing follows it in its clip).
std::vector<std::int8_t> contactEvents(const MotionDatabase& db, ContactEvent event);

struct TransitionCandidate {
  std::uint32_t from = 0;  ///< frame i
  std::uint32_t to = 0;    ///< frame j: pose i is close to pose j - 1
  float distance = 0;
};

struct TransitionSearchStats {
  std::size_t eventFrames = 0;  ///< frames at a contact event
  std::size_t pairs = 0;        ///< distances computed
  std::size_t belowThreshold = 0;
  std::size_t standingCutFrames = 0;  ///< cut points added where the performer stands still
};

/// The frames where the performer stands still enough to cut the graph at
/// (GraphParams::standingCuts): both feet planted over the kStandingCutSpacing_s either side
/// (inside the clip: the window ends where the clip does), and the whole body's angular
/// motion to the next frame (weighted as in the distance) no larger there than anywhere in
/// that window, the first of equal ones. Never a clip's last frame. Ascending global frames.
std::vector<std::uint32_t> standingCutFrames(const MotionDatabase& db, const FrameFeatures& features);

/// Every transition i -> j with frames i and j - 1 in the same contact-event class, their
/// distance below params.threshold and (if params.localMinimum) not larger than at any
/// neighbouring candidate pair: the previous and next event frames of the same clip, in
/// either frame. With ContactEvent::None these are the 8 neighbours in the distance matrix,
/// as in Lee et al. 2002. With standing cuts (GraphParams::standingCutsFor() the capture's
/// length), standingCutFrames() not at a contact event form one more class. The pairs are computed in bands of rows on
/// params.threads threads, never stored as a whole matrix. Sorted by (from, to); deterministic.
std::vector<TransitionCandidate> findTransitions(const MotionDatabase& db, const FrameFeatures& features,
                                                 const GraphParams& params, TransitionSearchStats* stats = nullptr);

}  // namespace mgrl
