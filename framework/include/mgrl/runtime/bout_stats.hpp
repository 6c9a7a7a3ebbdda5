#pragma once
/// \file
/// Measures of bouts, real or synthesized (docs/stats.md): a bout is the motions
/// of its fighters in one shared world frame. Distances, facing, strikes and landed
/// strikes, planted-foot speed, root direction reversals, joint steps and
/// interpenetration, per bout and pooled over bouts, plus the Wasserstein-1 distance that
/// `mgrl stats --compare` puts between two groups.

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/motion.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl {

/// Thresholds of the measures, SI units.
struct StatsParams {
  /// A strike lands when its fist or toe tip comes within this distance of the surface of
  /// one of the opponent's body capsules (m).
  double landRadius_m = 0.15;
  /// A strike is blocked when its tip comes within this distance of the axis of one of the
  /// opponent's forearms (elbow to fist tip) before it lands (m; 0: nothing blocks). The
  /// runtime world's guard radius plus its fist radius (WorldParams: 0.06 + 0.05).
  double blockRadius_m = 0.11;
  /// Pelvises closer than this on the ground count as interpenetrating (m).
  double closeDistance_m = 0.35;
  /// Root ground speeds below this are standing still for the reversal count (m/s).
  double reversalMinSpeed_mps = 0.2;
  /// Body capsule radii (m): pelvis-chest, chest-neck, head-head top; the runtime world's
  /// defaults (WorldParams), so the stats judge bodies as the world does.
  double spineRadius_m = 0.14, chestRadius_m = 0.16, headRadius_m = 0.11;
  AnnotationParams annotation;

  /// Throws mgrl::Error naming the first value out of range.
  void validate() const;
};

/// How the fighters of a bout are paired.
enum class Pairing {
  /// Each fighter's opponent at a frame is the nearest other fighter then (real capture,
  /// any number of fighters).
  Nearest,
  /// Fighters 2k and 2k+1 are partners (mgrl simulate's avatar_NNN.bvh; World pairs i with
  /// i ^ 1); an odd one out has no opponent.
  Partners,
};
const char* pairingName(Pairing pairing);

/// One fighter: the motion in metres with what the measures need, frame by frame.
struct Fighter {
  std::string source;
  std::size_t frames = 0;
  double frameTime = 0;
  SkeletonRoles roles;
  Annotation annotation;
  std::size_t joints = 0;
  /// Every joint's world position, frame-major: positions[f * joints + j].
  std::vector<Eigen::Vector3d> positions;
  /// Capsule points per frame: pelvis, chest, neck, head, head top, and each forearm's elbow
  /// and fist tip (9 per frame).
  std::vector<Eigen::Vector3d> body;
  /// The facing direction on the ground (unit, x and z) per frame, from the annotation's
  /// avatar frame (DESIGN.md sec. 3: the root's forward axis projected on the ground).
  std::vector<Eigen::Vector2d> facing;

  Eigen::Vector2d ground(std::size_t frame) const;  ///< root (pelvis) on the ground plane: (x, z)
  const Eigen::Vector3d& joint(std::size_t frame, std::size_t j) const { return positions[frame * joints + j]; }
};

/// Builds a fighter from a motion in metres. Throws mgrl::Error if a role is missing.
Fighter makeFighter(const Motion& motion, std::string source, const StatsParams& params);

struct Bout {
  std::string name;
  Pairing pairing = Pairing::Nearest;
  std::vector<Fighter> fighters;  ///< same frame count and frame time
};

/// Loads a bout's files (BVH, `units: auto`): at least two, one frame time (else
/// mgrl::Error naming both files and times). Files with different frame counts are cut to
/// the shortest, with a warning to `warn`. Pairing: Partners when every file is named
/// avatar_NNN.bvh (simulate's output), else Nearest. Malformed files throw ParseError.
Bout loadBout(const std::string& name, const std::vector<std::filesystem::path>& files, const StatsParams& params,
              const WarningSink& warn = {});

/// The samples and counts of one bout, or of several pooled.
struct BoutStats {
  std::string name;
  std::size_t bouts = 0, fighters = 0, frames = 0;
  double seconds = 0;         ///< bout time (sum over bouts)
  double fighterSeconds = 0;  ///< fighters x time
  std::vector<double> fps;    ///< frame rate of each bout
  /// Per fighter-frame with an opponent: pelvis distance on the ground (m) and the angle
  /// between the facing direction and the direction to the opponent's pelvis (deg, 0-180).
  std::vector<double> distance_m, facing_deg;
  /// Per foot and contact frame: the slower of ankle and toe on the ground plane (m/s).
  std::vector<double> plantedFootSpeed_mps;
  /// The same frames, each foot joint on its own: the ankle's and the toe's ground speed
  /// (m/s). A foot held by its ankle while its toe sweeps round shows only here (the
  /// world's foot lock once pinned the ankle, and the slower of the two read 0).
  std::vector<double> plantedAnkleSpeed_mps, plantedToeSpeed_mps;
  /// Per joint and frame-to-frame step: the joint's displacement (m), and that over the
  /// frame time (m/s: comparable across frame rates).
  std::vector<double> jointStep_m, jointSpeed_mps;
  /// Per fighter and frame-to-frame step: root ground speed (m/s); reversals among them.
  std::size_t rootSteps = 0, reversals = 0;
  std::size_t punches = 0, kicks = 0, landed = 0, blocked = 0;
  /// Each fighter's own strikes, in the bout's file order (strikes thrown, landed
  /// and blocked each way).
  struct Side {
    std::string source;
    std::size_t strikes = 0, landed = 0, blocked = 0;
    double seconds = 0;
  };
  std::vector<Side> sides;
  /// Over the pairs of the bout (simulate's partners 2k and 2k+1, or the two fighters of a
  /// two-fighter bout): the landed strikes of the side of each pair that landed more, and
  /// of both sides. Their ratio is the share the stronger side lands: 50 % an even bout,
  /// 100 % a one-sided one.
  std::size_t landedByMore = 0, landedInPairs = 0;
  /// Fighter-frames with an opponent; those with pelvises close; those with capsules overlapping.
  std::size_t pairFrames = 0, closeFrames = 0, overlapFrames = 0;
  /// Fighter-frames in which one of the fighter's forearms (elbow to fist tip) runs inside one
  /// of the opponent's body capsules (its axis within the capsule's radius of the capsule's).
  std::size_t forearmInsideFrames = 0;
  /// Seconds of the frame-to-frame steps (sum over fighters), for reversals per second.
  double stepSeconds = 0;
};

/// Measures one bout.
BoutStats measureBout(const Bout& bout, const StatsParams& params);
/// Pools bouts: samples concatenated, counts and times summed.
BoutStats pool(const std::vector<BoutStats>& bouts, const std::string& name);

/// The q-quantile (0..1) of `values` with linear interpolation between order statistics;
/// NaN for none.
double quantile(std::vector<double> values, double q);
/// Wasserstein-1 (earth mover's) distance between the empirical distributions of two
/// samples: the integral of |F_a - F_b|. NaN if either is empty.
double wasserstein1(std::vector<double> a, std::vector<double> b);

}  // namespace mgrl
