#pragma once
/// \file
/// Root motion from the joint that carries it. mgrl takes the body's travel, height and
/// tilt from joint 0 (DESIGN.md sec. 3: the avatar frame lies under the root). CMU and SNU
/// files put the pelvis there; game exports often add a node above it (`Root`,
/// `joint_Root`) that stays at the origin while the hips travel. Such a motion is
/// re-expressed (whether its root stays still or moves too) so that joint 0 carries the pelvis's global transform every
/// frame and the joints from the old root down to the pelvis carry none: every joint below the pelvis keeps its global
/// position and rotation exactly.

#include <string>

#include "mgrl/motion/motion.hpp"

namespace mgrl {

/// What moveRootToPelvis() did, for reports and messages.
struct RootMotionReport {
  int joint = 0;              ///< the joint whose motion joint 0 now carries (0: unchanged)
  std::string jointName;      ///< its name in the file
  double fileRootTravel = 0;  ///< largest distance of the file's root from its first position (m)
  std::string sentence;       ///< one line for people: which joint, and why
};

/// How far (m) and how much (rad) joint 0 moves over `motion`, from its first frame.
struct RootExcursion {
  double travel = 0, turn = 0;
};
RootExcursion rootExcursion(const Motion& motion);

/// Joint 0 already carries the motion when `pelvis` is 0: returns `motion` unchanged and a
/// report with joint 0. Otherwise every joint on the path from joint 0 down to the pelvis,
/// except the pelvis, must have that path as its only child (a second branch would move if
/// its parent's transform changed); then joint 0 takes the pelvis's global rotation and
/// position each frame (it gains position and rotation channels if it had none), and the
/// joints on the path, the pelvis included, get identity rotations and zero translations
/// and offsets. Throws mgrl::Error naming the joint with a second branch, and which role
/// to set instead. `source` names the file in messages.
Motion moveRootToPelvis(const Motion& motion, int pelvis, std::string_view source, RootMotionReport& report);

}  // namespace mgrl
