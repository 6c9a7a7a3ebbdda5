#pragma once
/// \file
/// Skeleton roles: which joints are the fists, wrists, forearms, shoulders, ankles, toes,
/// head and pelvis. Found by name for CMU (BVH and ASF), SNU, Mixamo-like and `_L`/`_R`
/// namings; any role can be set explicitly.

#include <array>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/skeleton.hpp"

namespace mgrl {

enum class Side : unsigned char { Left = 0, Right = 1 };
inline const char* sideName(Side side) { return side == Side::Left ? "left" : "right"; }

/// Role name -> joint name, e.g. {"left_fist", "LeftHand"}. Role names are those of
/// roleNames().
using RoleOverrides = std::map<std::string, std::string, std::less<>>;

/// Every role name: left_fist, right_fist, left_wrist, ..., head, pelvis.
std::vector<std::string> roleNames();

/// Head-joint-to-head-top distance per rest-pose pelvis-to-head distance, where a file gives
/// no head top: CMU subject 13's (his head end site, 1.78 of 9.58 units; he stands 1.63 m).
inline constexpr double kHeadTopPerSpine = 0.186;

/// Joint indices of each role, plus geometry derived from the rest pose.
struct SkeletonRoles {
  std::array<int, 2> fist{}, wrist{}, forearm{}, shoulder{}, ankle{}, toe{};
  int head = -1, pelvis = -1;
  /// The fist tip (knuckles) per side: a point fixed on joint fistTipJoint, at
  /// fistTipOffset in that joint's frame. The farthest rest-pose point (joint or end site)
  /// under the fist joint; the fist joint itself if it has none.
  std::array<int, 2> fistTipJoint{};
  std::array<Eigen::Vector3d, 2> fistTipOffset{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  /// The head top: a point fixed on the head joint, at this offset in its frame. The head's
  /// end site, unless it has none or one shorter than a quarter of the neck-to-head bone
  /// (game exports' have zero length): then a point continuing the neck, kHeadTopPerSpine of
  /// the pelvis-to-head distance past the head joint (at least the neck-to-head bone again).
  Eigen::Vector3d headTopOffset = Eigen::Vector3d::Zero();
  /// Toe tip per side: the toe joint's End Site offset (zero if it has none).
  std::array<Eigen::Vector3d, 2> toeTipOffset{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  /// Facing direction and up direction in the root joint's frame (unit vectors), from the
  /// rest pose: up from pelvis to head, facing = (left hip - right hip) x up.
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  /// Rest-pose distance along `up` from the head top (headTopOffset) down to the lowest
  /// foot point (skeleton length units): the standing height, whichever way the rest pose
  /// lies, as long as the spine and a leg are straight in it.
  double restHeight = 0;
};

/// Each role's joint index in roleNames() order (left before right for sided roles).
std::vector<int> roleJointIndices(const SkeletonRoles& roles);

/// Finds every role. A skeleton without a fist joint (no finger or fist names) gets its
/// wrist as the fist, the wrist's end site as the fist tip, and one warning to `warn`
/// saying so. Throws mgrl::Error for an unknown role or joint in `overrides`, and for any
/// other role no joint matches, listing the names tried and the skeleton's joints.
/// `source` names the file in messages.
SkeletonRoles findRoles(const Skeleton& skeleton, const RoleOverrides& overrides = {},
                        std::string_view source = "skeleton", const WarningSink& warn = {});

/// Rest-pose standing height (see SkeletonRoles::restHeight) using whatever head and pelvis
/// it can find by name, or the vertical (Y) extent if it finds none. For unit detection.
double estimateRestHeight(const Skeleton& skeleton);

}  // namespace mgrl
