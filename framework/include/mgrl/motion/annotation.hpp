#pragma once
/// \file
/// Automatic annotation of unlabelled capture (Lee & Lee 2004, sec. 6.2): foot contacts
/// and effective punches with their hitting points.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "mgrl/motion/motion.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl {

/// Distance from the elbow to the knuckles, in forearms (elbow to wrist), below which the
/// punch thresholds scale down (Annotation::punchScale): a quarter of a forearm past the
/// wrist. CMU's fist tips reach 1.8 forearms, SNU's 1.3, a wrist 1.0.
inline constexpr double kFistReachPerForearm = 1.25;

/// Thresholds in SI units. Defaults suit 30 to 120 fps human capture.
struct AnnotationParams {
  /// A foot joint (ankle or toe) is near the ground within this height above its planted
  /// level (its 10th-percentile height within +-1 s); entering and leaving a contact use
  /// different thresholds (hysteresis), so contacts do not flicker.
  double contactHeightEnter_m = 0.05;
  double contactHeightExit_m = 0.08;
  /// ...and slower than this (m/s).
  double contactSpeedEnter_mps = 0.5;
  double contactSpeedExit_mps = 0.9;
  /// A punch is effective when the fist tip's velocity along the forearm axis (elbow to
  /// wrist) exceeds this (m/s; for a wrist standing in for the fist, this times
  /// Annotation::punchScale)...
  double punchMinSpeed_mps = 2.0;
  /// `punch_min_speed_mps: auto`: punchMinSpeed_mps is chosen from the capture's own fist
  /// speeds instead (autoPunchMinSpeed()), and the chosen value is reported.
  bool punchMinSpeedAuto = false;
  /// ...and the velocity is not opposed to the axis: the cosine of the angle between them
  /// is at least this.
  double punchMinAlignment = 0.5;
  /// ...and each punch (a run of such frames of one hand) drives the fist out from the body
  /// at one of its frames at least: the fist's velocity relative to the pelvis, along the
  /// forearm, reaches this (m/s). Arms that swing while the body walks or runs fail it.
  /// 0 turns this test off: every arm motion that passes the tests above counts.
  double punchMinBodySpeed_mps = 1.5;
  /// ...and, when this is above 0, a punch thrown while the body travels at least this fast
  /// (the pelvis's net ground speed over the 3 s around it) is an arm swing of walking or
  /// running unless the fist drives away from its shoulder at swingMaxReach_mps at one of
  /// its frames (both scaled like punchMinSpeed_mps for a wrist). 0 (the default) turns the
  /// test off; `mgrl init` sets 0.9 for new scenarios, which drops 230 of the 231 runs in a
  /// game studio's walks, runs and dashes and keeps every CMU boxing punch.
  double swingTravel_mps = 0;
  double swingMaxReach_mps = 2.0;
  /// Fist speeds above this are capture glitches (e.g. a 23 m/s spike in SNU 16_28_1),
  /// never effective hits.
  double punchMaxSpeed_mps = 15.0;
  /// No punch counts while the boxer is down (paper sec. 6.2 annotates punches of a
  /// standing boxer): while the head top is below this fraction of the standing height
  /// above the lower foot, arm swings are not effective. In [0, 1); 0 turns the rule off.
  /// 0.6 keeps crouches, weaving and deep stances (CMU's boxing and karate punches all
  /// stay above 0.68) and drops kneeling, sitting, lying and falling (SNU's sparring has
  /// take-downs: arms flail on the way down and on the floor).
  double knockdownHeadRatio = 0.6;
  /// A kick is effective (by analogy with the punch, paper sec. 6.2) when the toe tip's
  /// speed exceeds this (m/s), its component along the shin axis (knee to ankle) is at
  /// least kickMinAlignment of it, the toe tip is at least kickMinHeight_m above the floor
  /// (steps and shuffles stay below), and the fighter is on his feet. A kicking foot swings
  /// across the shin at its fastest (a plain front kick's toe: 9.8 m/s, cosine -0.08 with
  /// the shin), so any direction counts by default: 4 m/s finds 25 kick frames in a game
  /// studio's front-kick clip, 301 in SNU's sparring, none in CMU's, SNU's or that
  /// studio's walks and runs (the defaults before, 3 m/s and cosine 0.5: 0 and 73).
  double kickMinSpeed_mps = 4.0;
  double kickMinAlignment = 0.0;
  double kickMinHeight_m = 0.3;
  /// Toe speeds above this are capture glitches, never effective kicks.
  double kickMaxSpeed_mps = 25.0;

  /// Throws mgrl::Error naming the first out-of-range value.
  void validate() const;
};

/// Ground-plane frame of the avatar at one frame (DESIGN.md sec. 3): origin below the root
/// on the ground, +Z facing, +X to the avatar's left, Y up.
struct AvatarFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double yaw = 0;  ///< facing angle about +Y; 0 faces world +Z

  /// World point -> avatar frame.
  Eigen::Vector3d toAvatar(const Eigen::Vector3d& world) const;
};

/// One frame at which a fist moves as an effective punch (an "effective hitting point").
struct EffectiveHit {
  std::uint32_t frame = 0;
  Side hand = Side::Left;
  Eigen::Vector3d tipWorld = Eigen::Vector3d::Zero();   ///< fist tip, world (m)
  Eigen::Vector3d tipAvatar = Eigen::Vector3d::Zero();  ///< fist tip, avatar frame of that frame (m)
  double speed_mps = 0;                                 ///< fist tip speed
  double alongForearm_mps = 0;                          ///< its component along the forearm axis
};

/// A heel this much higher above its planted level than the ball (m) stands on the ball
/// alone, and the other way round (Annotation::footPivot).
inline constexpr double kPivotRise_m = 0.03;

struct Annotation {
  double groundY = 0;  ///< estimated floor height (m)
  /// contact[side][frame] is 1 while that foot is on the ground.
  std::array<std::vector<std::uint8_t>, 2> contact;
  /// footPivot[side][frame]: where on the foot it rests, 0 on the heel (the ankle), 1 on
  /// the ball (the toe joint), 0.5 flat: 0.5 plus half of how much higher the ankle stands
  /// above its planted level than the toe above its own, in kPivotRise_m, held in [0, 1].
  /// Every frame, down or not; playback's foot lock holds that point.
  std::array<std::vector<float>, 2> footPivot;
  /// Effective hitting points in frame order.
  std::vector<EffectiveHit> hits;
  /// Punches per hand: runs of consecutive effective frames.
  std::array<int, 2> punches{0, 0};
  /// Per hand, the factor on the punch speed thresholds for the effector this skeleton has:
  /// 1 for a fist tip at least kFistReachPerForearm forearms from the elbow, less for a
  /// wrist standing in for a fist (its speed about the elbow is that much lower).
  std::array<double, 2> punchScale{1.0, 1.0};
  /// Runs per hand that were fast enough but did not drive the fist out from the body
  /// (AnnotationParams::punchMinBodySpeed_mps): arm swings, not counted as punches.
  std::array<int, 2> swings{0, 0};
  /// Effective kicks (hand is the foot; tip is the toe tip, along the shin), frame order.
  std::vector<EffectiveHit> kicks;
  /// Kicks per foot: runs of consecutive effective frames.
  std::array<int, 2> kickCount{0, 0};
  /// Frames where a fist moved faster than punchMaxSpeed_mps (ignored as glitches).
  int glitchFrames = 0;
  /// Standing height (m): head top (SkeletonRoles::headTopOffset) above the lower foot's
  /// lowest point, 99th percentile over the frames with both feet on the ground (over
  /// frames with one foot down if there are none, else over all frames). From the motion,
  /// not the rest pose, whose feet or head may not stand as the person does.
  double standingHeight = 0;
  /// Frames the standingHeight came from.
  std::size_t standingFrames = 0;
  /// Frames where the head top was below knockdownHeadRatio * standingHeight (no
  /// effective punches there).
  std::size_t knockdownFrames = 0;
  /// Avatar frame at every frame.
  std::vector<AvatarFrame> frames;

  std::size_t contactFrames(Side side) const;
  std::size_t hitCount(Side side) const;
};

/// Annotates `motion` (metres). `roles` must come from the motion's skeleton. With
/// `params.punchMinSpeedAuto`, the punch threshold is chosen from this motion alone
/// (autoPunchMinSpeed()); a database chooses it over all its clips first.
Annotation annotate(const Motion& motion, const SkeletonRoles& roles, const AnnotationParams& params = {});

/// What `punch_min_speed_mps: auto` chose, and from what.
struct AutoPunchSpeed {
  double speed_mps = 0;     ///< the threshold chosen, for a fist tip (m/s)
  std::size_t samples = 0;  ///< frames whose speed it was chosen from
  bool fellBack = false;    ///< too few samples: the default threshold was kept
  bool clamped = false;     ///< the split fell outside [kAutoPunchMin_mps, kAutoPunchMax_mps]
  /// e.g. "punch threshold auto: 1.69 m/s, the Otsu split of 697 fist speeds (log scale)"
  std::string sentence() const;
};

/// Bounds on what `auto` may choose (m/s), and the samples it needs to choose at all.
inline constexpr double kAutoPunchMin_mps = 1.0, kAutoPunchMax_mps = 4.0;
inline constexpr std::size_t kAutoPunchMinSamples = 30;

/// The punch threshold from the capture's own distribution of fist speeds: every frame of
/// a boxer on his feet whose fist moves out along the forearm at 0.5 m/s or more (aligned
/// as punchMinAlignment asks, scaled to a fist tip by Annotation::punchScale) is a sample;
/// the threshold is Otsu's split of their logarithms (the between-class variance of a
/// 400-bin histogram over [0.5, 15] m/s, maximised), which separates the fast mode of
/// strikes from guards, feints and walking arms. On log speeds, because both modes are
/// skewed: linear splits land at the strikes' lower tail (CMU 13_17: 2.6 m/s, recall of the
/// hand-labelled strikes 0.71, against 1.69 m/s and 0.81 on the log scale). Fewer than
/// kAutoPunchMinSamples samples keep the default (2 m/s).
AutoPunchSpeed autoPunchMinSpeed(std::span<const Motion* const> motions, const SkeletonRoles& roles,
                                 const AnnotationParams& params);

/// Otsu's threshold of `values` over a `bins`-bin histogram on [lo, hi] (values outside
/// count in the end bins): the bin edge that maximises the between-class variance. `lo`
/// when there are fewer than two distinct bins.
double otsuThreshold(std::span<const double> values, double lo, double hi, int bins);

/// Standing heights outside this range (m) are unusual for an adult: likely a wrong unit,
/// a mislabelled head or a capture without standing frames.
inline constexpr double kUsualHeightMin_m = 1.2, kUsualHeightMax_m = 2.2;

/// A warning text when `annotation.standingHeight` is outside the usual range, e.g.
/// `x.bvh: standing height 0.95 m, expected 1.2 to 2.2 m for an adult: ...`; empty otherwise.
std::string unusualHeightWarning(const Annotation& annotation, std::string_view source);

/// For every f, the q-quantile of values[f - window .. f + window] (clipped to the ends):
/// the element at index floor(q (n - 1)) of the n window values in ascending order. What
/// annotate() takes for a foot's planted level (q = 0.1, one second each side). Keeps the
/// window sorted as it slides, so each frame costs a binary search and a short move
/// instead of a selection over the whole window. Values must not be NaN.
std::vector<double> windowQuantiles(std::span<const double> values, std::size_t window, double q);

}  // namespace mgrl
