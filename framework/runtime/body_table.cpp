// The body parts a punch can land on (paper sec. 6.6): capsules on the skeleton's spine,
// chest and head, and the forearms that block it, found once per motion database.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/motion/kinematics.hpp"
#include "mgrl/runtime/world.hpp"

namespace mgrl {

BodyTable makeBodyTable(const MotionDatabase& db) {
  const Skeleton& skeleton = *db.skeleton;
  BodyTable table;
  table.headJoint = db.roles.head;
  table.pelvisJoint = db.roles.pelvis;
  // The chain from the head down to the pelvis: head, neck, ..., pelvis.
  std::vector<int> chain;
  for (int j = table.headJoint; j >= 0; j = skeleton.joint(static_cast<std::size_t>(j)).parent) {
    chain.push_back(j);
    if (j == table.pelvisJoint) break;
  }
  if (chain.empty() || chain.back() != table.pelvisJoint || chain.size() < 2)
    throw Error(fmt::format("skeleton: expected the head joint '{}' below the pelvis joint '{}' in the hierarchy, "
                            "found it elsewhere; set the roles head and pelvis in the scenario",
                            skeleton.joint(static_cast<std::size_t>(table.headJoint)).name,
                            skeleton.joint(static_cast<std::size_t>(table.pelvisJoint)).name));
  // chain = head, neck, ..., pelvis. Neck: the head's parent (unless that is the pelvis);
  // chest: halfway between the neck and the pelvis along the chain.
  table.neckJoint = chain.size() > 2 ? chain[1] : chain[0];
  table.chestJoint = chain.size() > 3 ? chain[(1 + (chain.size() - 1)) / 2] : table.neckJoint;

  // Each arm: the fist joint and up to 3 joints above it, up to the shoulder, shoulder side
  // first (what a blocked strike turns).
  for (int side = 0; side < 2; ++side) {
    table.fistJoint[side] = db.roles.fist[side];
    std::vector<int>& arm = table.armJoints[side];
    for (int j = skeleton.joint(static_cast<std::size_t>(db.roles.fist[side])).parent; j > 0 && arm.size() < 3;
         j = skeleton.joint(static_cast<std::size_t>(j)).parent) {
      if (std::find(chain.begin(), chain.end(), j) != chain.end()) break;  // the spine: not the arm's
      arm.push_back(j);
      if (j == db.roles.shoulder[side]) break;
    }
    std::reverse(arm.begin(), arm.end());
  }

  const std::size_t joints = skeleton.jointCount();
  const auto head = static_cast<std::size_t>(table.headJoint);
  // Head top: the head's end site, else one head length (neck to head) above the head.
  const std::optional<Eigen::Vector3d>& end = skeleton.joint(head).endSite;
  table.points.resize(static_cast<std::size_t>(db.frameCount()) * BodyTable::kPoints * 3);
  std::vector<Eigen::Quaterniond> rotations(joints);
  std::vector<Eigen::Vector3d> positions(joints);
  for (std::size_t c = 0; c < db.clips.size(); ++c) {
    const Clip& clip = db.clips[c];
    for (std::size_t k = 0; k < clip.motion.frameCount(); ++k) {
      forwardKinematics(clip.motion, k, rotations, positions);
      const AvatarFrame& frame = clip.annotation.frames[k];
      Eigen::Vector3d top;
      if (end && end->norm() > 1e-6) {
        top = pointOnJoint(rotations, positions, head, *end);
      } else {
        const Eigen::Vector3d up = positions[head] - positions[static_cast<std::size_t>(table.neckJoint)];
        top = positions[head] + (up.norm() > 1e-6 ? up : Eigen::Vector3d(0, 0.2, 0));
      }
      auto fistTip = [&](int side) {
        return pointOnJoint(rotations, positions, static_cast<std::size_t>(db.roles.fistTipJoint[side]),
                            db.roles.fistTipOffset[side]);
      };
      const Eigen::Vector3d world[BodyTable::kPoints] = {positions[static_cast<std::size_t>(table.pelvisJoint)],
                                                         positions[static_cast<std::size_t>(table.chestJoint)],
                                                         positions[static_cast<std::size_t>(table.neckJoint)],
                                                         positions[head],
                                                         top,
                                                         positions[static_cast<std::size_t>(db.roles.forearm[0])],
                                                         fistTip(0),
                                                         positions[static_cast<std::size_t>(db.roles.forearm[1])],
                                                         fistTip(1)};
      float* out = table.points.data() + (static_cast<std::size_t>(db.offsets[c] + k) * BodyTable::kPoints) * 3;
      for (const Eigen::Vector3d& p : world) {
        Eigen::Vector3d local = frame.toAvatar(p);
        local.y() -= clip.annotation.groundY;
        *out++ = static_cast<float>(local.x());
        *out++ = static_cast<float>(local.y());
        *out++ = static_cast<float>(local.z());
      }
    }
  }
  return table;
}

}  // namespace mgrl
