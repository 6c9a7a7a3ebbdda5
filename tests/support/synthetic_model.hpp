#pragma once
/// \file
/// A synthetic state-action model of any size, shaped like a real boxing graph, so that
/// benchmarks can run on a problem as large as the paper's (Lee & Lee 2004, sec. 6.3: 437
/// states, 27,072 actions of 5 to 40 frames at 15 fps) without its capture data.
///
/// The defaults of SyntheticModelSpec were measured from scenarios/boxing.yaml on
/// 2026-11-21 (CMU subject 13, 13_17 + 13_18 at 30 fps: 117 states, 1438 actions of 4 to 70
/// frames, 208 effective hitting points, 3171 hits inside actions); the same graph built at
/// 15 fps (`--set motion.fps=15`: 89 states, 1028 actions) agrees where a number is quoted
/// twice. Only statistics were taken, never frames: the synthetic model has no poses, so it
/// feeds learners, rewards, discretizers and controllers, not playback or BVH export.
#include <array>
#include <cstddef>
#include <cstdint>

#include "mgrl/graph/state_action_model.hpp"

namespace mgrl {

/// A normal distribution cut to [min, max]: values outside are drawn again (after 64 misses,
/// which only bounds holding almost none of the mass cause, the mean is clamped into them).
struct BoundedNormal {
  double mean = 0, sd = 0, min = 0, max = 0;
};

/// What makeSyntheticModel builds. Units: metres, seconds, radians (DESIGN.md sec. 3);
/// positions in the avatar frame (+Z facing, +X left, Y up; angle atan2(x, z), 0 ahead).
struct SyntheticModelSpec {
  // --- Size: the paper's graph.
  std::size_t states = 437;    ///< at least 1
  std::size_t actions = 27072;  ///< at least `states` (every state needs an out-action)
  std::uint32_t minFrames = 5, maxFrames = 40;  ///< frames per action, uniform in [min, max]; 1 <= min <= max
  double fps = 15;             ///< frames per second, > 0
  std::uint64_t seed = 1;      ///< the same seed gives identical arrays

  // --- Graph shape. Boxing: out-actions per state mean 12.3, sd 8.9 (cv 0.72), min 2,
  // median 10, max 36, gamma-like; in-actions the same spread, correlation with out -0.29;
  // no action returns to the state it leaves.
  double outDegreeCv = 0.72;  ///< coefficient of variation of out-actions per state, >= 0 (0: all equal)
  double inDegreeCv = 0.72;   ///< same for in-actions (end states are drawn with gamma weights)
  /// Transition distances (boxing: mean 0.31, sd 0.06, 0.13 to 0.45; threshold 0.45).
  BoundedNormal transitionDistance{0.31, 0.063, 0.125, 0.45};

  // --- Root motion. The boxer stays in place: an action's displacement does not grow with
  // its length (boxing: sd of dx 0.07-0.11 m, dz 0.09-0.10 m, dyaw 0.27-0.58 rad in every
  // length bucket from 0.13 s to 2.3 s), while the root sways fast (per-frame speed sd
  // 0.30 m/s forward and sideways, turn-rate sd 2.34 rad/s; velocity autocorrelation
  // crosses 0 after about 0.28 s, and 0.18 s for turning, then goes negative). So the root
  // is a slow drift plus a sway: a damped oscillator driven by noise (a stationary AR(2)
  // process per coordinate, sampled at the spec's fps).
  /// Drift per action in the avatar frame, drawn once per action (boxing: per-frame means
  /// 0.033 m/s forward, 0.037 m/s to the left, 0.23 rad/s turning left).
  BoundedNormal driftForward_mps{0.033, 0.03, -0.3, 0.3};
  BoundedNormal driftSideways_mps{0.037, 0.03, -0.3, 0.3};
  BoundedNormal driftTurn_radps{0.23, 0.15, -2, 2};
  /// Sway of the ground position (each of x, z) and of the facing: stationary standard
  /// deviation, period and damping ratio (in [0, 1)) of the oscillator. The deviations are
  /// the boxing displacement sd / sqrt(2) (start and end of a long action are independent);
  /// periods and damping were fitted by generating a boxing-sized model at 30 fps until it
  /// showed boxing's per-frame speed sd (0.30 m/s, 2.34 rad/s; synthetic 0.30, 2.37) and
  /// velocity autocorrelation (boxing, lags of 1/30 s: forward 0.92 0.55 0.30 0.14 -0.02 -0.12
  /// at lags 1 3 5 7 9 11, synthetic 0.85 0.56 0.30 0.08 -0.06 -0.16; turning 0.89 0.45 0.16
  /// -0.09 -0.32 -0.49, synthetic 0.89 0.59 0.24 -0.10 -0.37 -0.53).
  double swayPositionSd_m = 0.067, swayPositionPeriod_s = 1.4, swayPositionDamping = 0.5;
  double swayYawSd_rad = 0.36, swayYawPeriod_s = 0.95, swayYawDamping = 0.2;

  // --- Effective hits (paper sec. 6.2).
  /// Centroid of all effective hitting points in the avatar frame (boxing: -0.045, 1.226,
  /// 0.418 m) and the fastest hit's speed (boxing: 8.70 m/s; > 0).
  std::array<double, 3> centroid{-0.045, 1.226, 0.418};
  double maxHitSpeed_mps = 8.70;
  /// Fraction of all actions holding hits (boxing: 465 of 1438 = 0.32). Hits need time to
  /// wind up: actions shorter than minHitActionSeconds hold none (boxing: 5 % of actions
  /// under 0.6 s hold hits, 70 % of longer ones), the others are picked at random.
  double hitActionFraction = 0.32;
  double minHitActionSeconds = 0.6;
  /// Relative frequency of 1, 2, 3 and 4 punches in an action with hits (boxing: 219, 177,
  /// 18, 51 of 465). A punch is a run of consecutive hitting frames of one hand.
  std::array<double, 4> punchCountWeights{0.47, 0.38, 0.04, 0.11};
  /// Duration of a punch (boxing: mean 0.133 s, sd 0.066, 1 to 8 frames at 30 fps), so
  /// about 2 hitting frames at 15 fps; at least one frame.
  BoundedNormal punchSeconds{0.133, 0.066, 0.033, 0.267};
  double rightHandFraction = 0.83;  ///< boxing: 83 % of the hits in actions are right-handed
  /// Where a punch's middle frame is, seen from the decision (boxing, hits in actions:
  /// angle left hand 0.87 +- 0.50 rad, right hand 0.38 +- 0.44, all within -2.33 to 1.78;
  /// ground distance 0.655 +- 0.20 m within 0.27 to 1.26; height 1.20 +- 0.26 m within 0.56
  /// to 1.69). The bounds become the hit grid's bounding volume.
  std::array<BoundedNormal, 2> hitAngle_rad{BoundedNormal{0.87, 0.50, -2.33, 1.78},
                                            BoundedNormal{0.38, 0.44, -2.33, 1.78}};  ///< [left, right]
  BoundedNormal hitDistance_m{0.655, 0.20, 0.27, 1.26};
  BoundedNormal hitHeight_m{1.20, 0.26, 0.56, 1.69};
  /// How a punch's point moves from frame to frame (boxing, consecutive hitting frames:
  /// +0.12 rad, +0.11 m outwards, +0.067 m up per 1/30 s).
  double punchAngleRate_radps = 3.65, punchDistanceRate_mps = 3.3, punchHeightRate_mps = 2.0;
  /// Hit weight: fist speed / maxHitSpeed_mps (boxing: 0.53 +- 0.15 within 0.25 to 1).
  BoundedNormal hitWeight{0.53, 0.15, 0.25, 1.0};

  /// Throws mgrl::Error naming the first out-of-range member, e.g.
  /// `synthetic model: actions: expected at least states = 437 (...), found 100`.
  void validate() const;
};

/// Builds a model with exactly spec.states states and spec.actions actions that passes
/// checkModel: every state has at least one out-action and their number varies; the states
/// form one strongly connected graph (a cycle 0 -> 1 -> ... -> 0 runs through them, the
/// other actions end at random states); actions are sorted by the state they leave.
///
/// Frames: each state has a frame and each action a run of its own frames before its end
/// state's frame, so framesTotal = states + sum over actions of (length - 1), every frame is
/// in the component, and only an action's last frame is a state's. Clips, transitions and
/// frameEntersTransition describe that frame graph: a state's frame ends its clip, every
/// action enters through a transition, and it reaches its end state through one too unless
/// it is the cycle action whose run precedes that state's frame in the same clip.
///
/// Deterministic: the same spec gives identical arrays (mgrl::Rng draws; results can differ
/// in the last bits only where two C libraries round sin, cos or log differently). Fast:
/// about 0.1 s for the paper's size. Throws mgrl::Error for an invalid spec (validate) or a
/// model whose frames do not fit 32-bit indices.
StateActionModel makeSyntheticModel(const SyntheticModelSpec& spec);

}  // namespace mgrl
