#pragma once
/// \file
/// Body signals along an action (scenarios/README.md, "reward terms"): what the reward
/// vocabulary and the success criteria measure at the action's frames, from the
/// state-action model alone. Frame t of action a (1 = the first frame after the decision)
/// is the model's action frame actionFrameBegin[a] + t - 1; the target e is in the
/// decision's avatar frame (DESIGN.md sec. 3: +Z facing, +X left, Y up), as the learners
/// see it.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

/// A point of the body a distance (or, for effort, a speed) is measured at: the
/// effective hitting points' centroid, the pelvis's ground point, or a joint of the
/// skeleton named by a role (left_fist, head, ...: roleNames()) or by its own name.
struct BodyPoint {
  enum class Kind {
    Centroid,  ///< the effective hitting points' centroid carried along (the paper's p(t), sec. 6.4)
    Pelvis,    ///< the ground point below the root (the avatar frame's origin)
    Joint,     ///< a joint, `joint` in StateActionModel::jointNames once bound
    Body,      ///< every joint (effort only: their mean speed)
  };
  Kind kind = Kind::Centroid;
  std::string name = "centroid";  ///< as written: "centroid", "pelvis", "body", a role or a joint
  int joint = -1;                 ///< Joint: its index, after bindBodyPoint(); -1 before

  static BodyPoint centroid() { return {}; }
  static BodyPoint pelvis() { return {Kind::Pelvis, "pelvis", -1}; }
  bool operator==(const BodyPoint&) const = default;
};
/// "centroid", "pelvis", "body"; any other name is a joint, found later by bindBodyPoint().
BodyPoint parseBodyPoint(std::string_view name);
std::string_view bodyPointName(const BodyPoint& point);

/// Finds a Joint point's joint in `m` (a role first, then a joint's own name). Returns
/// false if the model has no such joint (or, for Body, no joints at all); `why` then says
/// which roles and joints it has.
bool bindBodyPoint(const StateActionModel& m, BodyPoint& point, std::string* why);

/// Which limbs' effective strikes count: a bit set of the four effectors.
enum Effector : std::uint8_t {
  kLeftFist = 1,
  kRightFist = 2,
  kLeftFoot = 4,
  kRightFoot = 8,
  kFists = kLeftFist | kRightFist,
  kFeet = kLeftFoot | kRightFoot,
  kAnyLimb = kFists | kFeet,
};
/// "left_fist", "right_fist", "fists", "left_foot", "right_foot", "feet", "any".
std::uint8_t parseEffector(std::string_view name);
inline constexpr const char* kEffectorNames[] = {"fists",     "left_fist",  "right_fist", "feet",
                                                 "left_foot", "right_foot", "any"};

/// The ground (dims 2) or 3-D (dims 3; not the pelvis's ground point) distance from the
/// body point to the target at action frame `frame` (a global action-frame index). A
/// joint point must be bound (bindBodyPoint) to `m`.
double bodyDistance(const StateActionModel& m, std::size_t frame, const BodyPoint& point, int dims,
                    const Eigen::Vector3d& e);

/// A joint's position at action frame `frame`, in the decision's avatar frame (m).
Eigen::Vector3d jointAt(const StateActionModel& m, std::size_t frame, int joint);

/// The speed (m/s) of a bound joint point at action frame `frame` in the capture it plays,
/// or for Body the mean speed of every joint.
double bodySpeed(const StateActionModel& m, std::size_t frame, const BodyPoint& point);

/// The unsigned angle (radians, [0, pi]) between the avatar's facing at `frame` and the
/// ground direction from it to the target; 0 when the target is straight ahead.
double facingError(const StateActionModel& m, std::size_t frame, const Eigen::Vector3d& e);
/// The same angle signed (radians, (-pi, pi]): positive with the target to the avatar's
/// left (+X of its frame), negative to its right.
double signedFacing(const StateActionModel& m, std::size_t frame, const Eigen::Vector3d& e);

/// The avatar's ground speed at offset t of action a (m/s): its root's displacement from
/// frame t - 1 (the decision at t = 1) to frame t, over the frame time.
double rootSpeed(const StateActionModel& m, std::size_t a, std::size_t t);

/// The best effective strike of the `effectors` landing within `radius` of e at offset t
/// of action a: its speed weight (or 1 without use_speed), 0 if none lands. Punches come
/// from m.hits, kicks from m.kicks.
double strikeAt(const StateActionModel& m, std::size_t a, std::uint32_t t, std::uint8_t effectors, double radius,
                bool useSpeed, const Eigen::Vector3d& e);

/// Where a striker's effective strikes reach (the `avoid` term and success
/// condition): every effective strike tip of the `effectors` in `m` (punches from m.hits,
/// kicks from m.kicks), seen from the striker's own avatar frame at the strike's frame (its
/// root on the ground, +Z its facing). An opponent that is another avatar of the same
/// graph strikes at these points around itself. distance() answers "how far is a point from
/// the nearest of them" from a distance field precomputed once (4 cm cells, trilinear), so a
/// reward evaluated for every vertex and action pays a lookup, not a scan of the strikes.
class StrikeReach {
 public:
  /// `cap`: distances are exact up to cap (m, in (0, 1]) and cap beyond. Throws mgrl::Error
  /// if `m` has no effective strike of the effectors.
  StrikeReach(const StateActionModel& m, std::uint8_t effectors, double cap);
  /// The distance (m) from `p`, in the striker's avatar frame, to the nearest strike tip;
  /// at most cap.
  double distance(const Eigen::Vector3d& p) const;
  /// The strike tips (deduplicated to 1 cm), striker's avatar frame.
  const std::vector<Eigen::Vector3f>& tips() const { return tips_; }
  double cap() const { return cap_; }

 private:
  static constexpr double kCell = 0.04;  ///< the field's cell size (m)
  std::vector<Eigen::Vector3f> tips_;
  Eigen::Vector3d origin_;  ///< the field's first cell centre
  double cap_ = 0;
  int n_[3] = {0, 0, 0};
  std::vector<float> field_;  ///< n_[0] x n_[1] x n_[2], x fastest
};

/// A point of the decision's avatar frame seen from an opponent standing at e.position (on
/// the ground; its height is ignored) facing e.heading (rad, from +Z towards +X): in the
/// opponent's own avatar frame.
Eigen::Vector3d inOpponentFrame(const TargetState& e, const Eigen::Vector3d& p);

/// How far joint `joint` is, at action frame `frame`, from being reached by an opponent
/// standing at e: the smaller of its distance to the opponent's strike tips and
/// the ground gap between the two bodies (the avatar's pelvis to the opponent's ground
/// point, less two `bodyRadius`: bodies overlap below 0). Never below 0, at most reach.cap().
double opponentClearance(const StateActionModel& m, std::size_t frame, int joint, const StrikeReach& reach,
                         const TargetState& e, double bodyRadius);

/// Where a learned opponent is at one frame of the avatar's action, in the
/// avatar frame of the avatar's decision: it plays frame `offset` (1 = the first after its
/// decision) of `action`, which it decided on with its root at `decision`.
struct OpponentFrame {
  GroundMotion decision;
  std::uint32_t action = 0, offset = 0;
  double cosYaw = 1, sinYaw = 0;  ///< of decision.dyaw, computed once per opponent decision
  std::size_t frame(const StateActionModel& m) const { return m.actionFrameBegin[action] + offset - 1; }
  /// A point of the opponent's decision frame (its action's, as jointAt() and ActionHit
  /// give them) in the avatar's decision frame: applyMotion(decision, p), without a sine.
  Eigen::Vector3d toAvatar(const Eigen::Vector3d& p) const {
    return {decision.dx + cosYaw * p.x() + sinYaw * p.z(), p.y(), decision.dz - sinYaw * p.x() + cosYaw * p.z()};
  }
  /// Its root's ground point at this frame, in the avatar's decision frame (height 0).
  Eigen::Vector3d ground(const StateActionModel& m) const {
    const double* r = &m.frameRoot[3 * frame(m)];
    return toAvatar({r[0], 0, r[1]});
  }
};

/// The model's head joint (the `head` role), or -1 if its skeleton has none: where a learned
/// opponent is aimed at (opponentTarget()).
int headJoint(const StateActionModel& m);

/// What a learned opponent offers as the target at one frame, in the avatar's
/// decision frame: its head (joint `head` of `m`), or with head < 0 its root's ground point
/// at `height`. The reward terms and the success conditions read the same point.
Eigen::Vector3d opponentTarget(const StateActionModel& m, const OpponentFrame& o, int head, double height);

/// The root motion from action a's decision to its frame k (k = 0: none).
GroundMotion actionFrameMotion(const StateActionModel& m, std::size_t a, std::uint32_t k);
/// `b` expressed in the frame `a` leads to, composed: the frame b leads to from a's start.
GroundMotion composeMotion(const GroundMotion& a, const GroundMotion& b);
/// The point p of the frame `g` leads to, seen from g's start.
Eigen::Vector3d applyMotion(const GroundMotion& g, const Eigen::Vector3d& p);
/// A learned opponent's root at frame f, in the avatar's decision frame.
inline GroundMotion opponentRootAt(const StateActionModel& m, const OpponentFrame& f) {
  return composeMotion(f.decision, actionFrameMotion(m, f.action, f.offset));
}

/// A learned opponent's discrete state (TargetState::opponent): `endState`, the
/// graph state its current action ends at, and the phase bucket of the `framesLeft` (in [1,
/// length]) of that action's `length` frames, out of `phases` (bucket 0: about to arrive).
inline std::int32_t opponentStateIndex(std::uint32_t endState, std::uint32_t framesLeft, std::uint32_t length,
                                       int phases) {
  const auto p = static_cast<std::uint32_t>(phases);
  return static_cast<std::int32_t>(endState * p + std::min<std::uint32_t>(p - 1, (framesLeft - 1) * p / length));
}

/// The best effective strike of the `effectors` that a learned opponent at its frame `o`
/// lands within `radius` of joint `joint` of the avatar at its action frame `frame` (a
/// strike counts at its effective frame only, as the world checks it): its speed
/// weight (or 1 without use_speed), 0 if none lands. `contact` seen from the other side.
double trackedStrikeAt(const StateActionModel& m, std::size_t frame, int joint, const OpponentFrame& o,
                       std::uint8_t effectors, double radius, bool useSpeed);

/// How far joint `joint` of the avatar, at its action frame `frame`, is from the opponent's
/// actual strikes at its frame `o`: the distance to the tip of each effective
/// strike of the `effectors` that its action throws within `window` frames of o, and the
/// ground gap between the bodies (pelvis to the opponent's root, less two bodyRadius).
/// Never below 0, at most cap.
double trackedClearance(const StateActionModel& m, std::size_t frame, int joint, const OpponentFrame& o,
                        std::uint8_t effectors, std::uint32_t window, double cap, double bodyRadius);

}  // namespace mgrl
