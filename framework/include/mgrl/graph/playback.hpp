#pragma once
/// \file
/// Playing actions of a state-action model back as poses, with transition blending
/// (Lee et al. 2002, sec. 4.3 style): when an action enters through a transition, the pose
/// difference between the frame left and the frame the new clip expected is carried as a
/// per-joint offset that fades out over a few frames, so playback never jumps. The root is
/// placed by composing the actions' ground motions; while offsets fade, the root is shifted
/// so that planted feet do not slide, and the shift stays with the avatar.
#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/motion/motion_database.hpp"

namespace mgrl {

/// A full pose: local rotation and local translation of every joint (the root's
/// translation in world coordinates, metres, ground at y = 0).
struct Pose {
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  /// The Skeleton::id() whose offsets `translations` holds for the joints without
  /// position channels, as ActionPlayback::next() wrote them (it then rewrites only the
  /// others: storing 10,000 poses' constant offsets every frame was a tenth of a posed
  /// crowd's time); 0 for none. An id, not an address, so that a skeleton built
  /// where another was freed is not taken for it. Whoever changes those translations
  /// otherwise, or clears and resizes `translations` to the same size, resets it to 0.
  std::uint64_t offsetsOf = 0;
};

/// Every frame of the capture posed once, as playback shows a frame outside a transition's
/// blend: per frame, each joint's global rotation and its position relative to the root,
/// with the avatar's yaw removed (the root at the origin, turned by its tilt only), and the
/// root's tilt, height and offset from the avatar origin. With it, ActionPlayback poses such
/// a frame by turning these about the vertical and moving them to the root, instead of
/// forward kinematics. frames x joints x 56 bytes (boxing: 3.4 MB); shared by
/// any number of playbacks, read only.
struct SourcePoses {
  std::size_t joints = 0;
  std::vector<Eigen::Quaterniond> globals;   ///< frame-major, frame * joints + joint
  std::vector<Eigen::Vector3d> positions;    ///< frame-major, relative to the root
  std::vector<Eigen::Quaterniond> rootTilt;  ///< the root's local rotation, yaw removed
  std::vector<double> height;                ///< the root above the clip's ground (m)
  std::vector<Eigen::Vector2d> rootOffset;   ///< the root from the avatar origin (x, z)
  std::uint32_t frameCount() const { return static_cast<std::uint32_t>(height.size()); }
};

/// Poses every frame of `db` as above (one forward-kinematics pass per frame).
SourcePoses makeSourcePoses(const MotionDatabase& db);

class ActionPlayback {
 public:
  /// `db` and `model` must outlive the playback; blendFrames >= 0 (0: no blending).
  /// lockFeet: while a transition blends, shift the root so planted feet stay put (the
  /// shift stays with the avatar). Off, the root follows the model's ground motion
  /// exactly, as the world simulation and the learners assume.
  ActionPlayback(const MotionDatabase& db, const StateActionModel& model, int blendFrames, bool lockFeet = true);

  /// Stands the avatar at state `state`, its avatar frame at world (dx, dz, dyaw).
  void reset(std::uint32_t state, const GroundMotion& world = {});
  /// Plays action `action`, which must leave the current state (throws mgrl::Error if
  /// not), appending one pose per frame to `out`; afterwards the avatar is at the action's
  /// end state.
  void play(std::uint32_t action, std::vector<Pose>& out);

  /// The same one frame at a time, into a caller-owned pose (no allocation once `pose`
  /// has its size): begin() checks and starts the action, next() writes its next frame and
  /// returns false (writing nothing) once the action is over; the avatar is then at the
  /// action's end state.
  void begin(std::uint32_t action);
  bool next(Pose& pose);
  /// World joint positions and rotations of the last pose next() wrote.
  std::span<const Eigen::Vector3d> positions() const { return fkPositions_; }
  std::span<const Eigen::Quaterniond> globalRotations() const { return fkRotations_; }
  /// The same, writable, for a caller that deforms the pose next() wrote (the world's hit
  /// reaction) without copying it: next() overwrites both and never reads them back.
  std::span<Eigen::Vector3d> positions() { return fkPositions_; }
  std::span<Eigen::Quaterniond> globalRotations() { return fkRotations_; }

  std::uint32_t state() const { return state_; }
  /// Planted feet: while the annotation has a foot on the ground, the
  /// whole foot is held: the point it rests on (Annotation::footPivot: heel, ball or
  /// between) stays where it landed on the floor (its height follows the motion), the
  /// foot keeps its heading (up to a pivot when the body turns far) and half of the
  /// motion's roll from heel to toe, by two-bone inverse kinematics of hip, knee and ankle;
  /// it is let go over a few frames when it lifts. Rotations only, so bone lengths never
  /// change. Off by default.
  void setFootLock(bool on) { footLock_ = on; }
  /// Poses frames outside a blend from `poses` (made by makeSourcePoses() from this
  /// playback's database; it must outlive the playback), which gives the same poses as
  /// forward kinematics up to rounding. nullptr: forward kinematics for every frame.
  /// Throws mgrl::Error if `poses` is not the database's size.
  void setSourcePoses(const SourcePoses* poses);
  /// Moves the avatar by (dx, dz) on the floor (world, m) from the next pose on; the shift
  /// stays with it (the world pushes overlapping bodies apart this way).
  void nudge(double dx, double dz) { correction_ += Eigen::Vector2d(dx, dz); }
  /// The avatar frame at the current state, in world coordinates.
  const GroundMotion& world() const { return world_; }
  /// The source frame shown by the last pose.
  std::uint32_t frame() const { return frame_; }

 private:
  struct Local {                                // a pose with the root's yaw and ground position factored out
    std::vector<Eigen::Quaterniond> rotations;  // root: tilt (yaw removed)
    double height = 0;
    Eigen::Vector2d rootOffset = Eigen::Vector2d::Zero();  // root from the avatar origin (x, z)
  };
  void sourceLocal(std::uint32_t frame, Local& out) const;

  const MotionDatabase& db_;
  const StateActionModel& model_;
  int blendFrames_;
  bool lockFeet_;
  std::uint32_t state_ = 0, frame_ = 0;
  std::uint32_t action_ = 0;
  std::size_t cursor_ = 0, end_ = 0;  ///< action frames still to play: [cursor_, end_)
  GroundMotion world_;
  /// current_: the pose shown last, as Local. Each frame leaves it stale (it is then
  /// sourceLocal(frame_) blended at shownAlpha_); only a transition needs it, and
  /// refreshCurrent() computes it then, with the same arithmetic.
  Local current_, previous_;
  bool currentStale_ = false;
  double shownAlpha_ = 0;
  void refreshCurrent();
  void blend(double alpha, std::span<Eigen::Quaterniond> rotations) const;
  const SourcePoses* sourcePoses_ = nullptr;
  std::vector<Eigen::Quaterniond> offset_;
  /// Per joint, the offset as an angle and axis, found once per transition: the blended
  /// rotation of each frame is then one sine and cosine, not a full slerp.
  std::vector<double> offsetHalfAngle_;
  std::vector<Eigen::Vector3d> offsetAxis_;
  double heightOffset_ = 0;
  int sinceTransition_ = 1 << 30;
  Eigen::Vector2d correction_ = Eigen::Vector2d::Zero();  // world (x, z) shift from foot locking
  std::vector<Eigen::Quaterniond> fkRotations_;
  std::vector<Eigen::Vector3d> fkPositions_;
  std::array<Eigen::Vector3d, 2> previousAnkle_;
  std::array<bool, 2> previousDown_{false, false};
  bool havePrevious_ = false;
  // Foot locking by IK: per foot, whether it is held, where, and the release's progress.
  bool lockFoot(int side, bool down, double pivot, Pose& pose);
  bool footLock_ = false;
  std::array<bool, 2> held_{false, false};
  std::array<Eigen::Vector3d, 2> anchor_;
  /// The held foot's twist about the vertical: cosine and sine of half its angle.
  std::array<Eigen::Vector2d, 2> anchorHeading_{Eigen::Vector2d(1, 0), Eigen::Vector2d(1, 0)};
  /// The held foot's ankle-to-ball vector on the floor plane (x, z) at the last frame.
  std::array<Eigen::Vector2d, 2> lastHeldBall_{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  std::array<Eigen::Quaterniond, 2> heldRotation_{Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()};
  std::array<double, 2> lastAnkleY_{0.0, 0.0};
  std::array<int, 2> releasing_{1 << 30, 1 << 30};
  std::array<int, 2> knee_{-1, -1}, hip_{-1, -1};
  /// Per leg, the hip and every joint below it: what a foot lock changes.
  std::array<std::vector<int>, 2> leg_;
};

/// Poses as a motion clip on `skeleton` (for export): every joint's rotation, and the
/// translation of each joint with position channels. Throws mgrl::Error for no pose.
Motion motionFromPoses(std::shared_ptr<const Skeleton> skeleton, const std::vector<Pose>& poses, double frameTime);

/// Foot sliding: mean horizontal speed (m/s) of a foot's ankle over pairs of consecutive
/// frames in which the annotation has that foot planted in both.
struct FootSlide {
  double meanSpeed_mps = 0;
  std::size_t framePairs = 0;
};

/// Statistics of a seeded random walk through the graph, played with blending.
struct PlaybackCheck {
  std::size_t frames = 0, actions = 0, transitions = 0;
  FootSlide slide;
  /// The capture's own ankle speed at the same played frames (each from its source
  /// predecessor): the fair baseline for `slide`.
  double sourceSlideSameFrames_mps = 0;
  /// Foot sliding of the whole capture, every clip.
  FootSlide captureSlide;
  /// Largest frame-to-frame move of any joint (m), in playback and in the source clips.
  double maxJointStep_m = 0, sourceMaxJointStep_m = 0;
  /// Largest step ratio playback / source over joints (<= 1: no jump beyond the data's).
  double worstJointStepRatio = 0;
  int worstJoint = -1;  ///< the joint with that ratio
};

/// Plays `actions` random actions from a random state with `seed` and measures sliding
/// and joint steps against the source.
PlaybackCheck checkPlayback(const MotionDatabase& db, const StateActionModel& model, int blendFrames,
                            std::size_t actions, std::uint64_t seed);

}  // namespace mgrl
