#include "mgrl/motion/root_motion.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/kinematics.hpp"

namespace mgrl {

namespace {

bool hasRotationChannel(const Joint& joint) {
  return std::any_of(joint.channels.begin(), joint.channels.end(),
                     [](const Channel& c) { return c.kind == Channel::Kind::Rotation; });
}

// Joints from joint 0 down to `pelvis`, both included, in order.
std::vector<int> pathTo(const Skeleton& skeleton, int pelvis) {
  std::vector<int> path;
  for (int j = pelvis; j >= 0; j = skeleton.joint(static_cast<std::size_t>(j)).parent) path.push_back(j);
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace

RootExcursion rootExcursion(const Motion& motion) {
  RootExcursion out;
  const Eigen::Vector3d first = motion.localTranslation(0, 0);
  const Eigen::Quaterniond turn0 = motion.rotation(0, 0);
  for (std::size_t f = 0; f < motion.frameCount(); ++f) {
    out.travel = std::max(out.travel, (motion.localTranslation(f, 0) - first).norm());
    out.turn = std::max(out.turn, motion.rotation(f, 0).angularDistance(turn0));
  }
  return out;
}

Motion moveRootToPelvis(const Motion& motion, int pelvis, std::string_view source, RootMotionReport& report) {
  const Skeleton& skeleton = motion.skeleton();
  const RootExcursion excursion = rootExcursion(motion);
  report = {};
  report.fileRootTravel = excursion.travel;
  report.jointName = skeleton.joint(0).name;
  if (pelvis <= 0) {
    report.sentence = fmt::format("root motion from '{}', the file's root (the pelvis role)", skeleton.joint(0).name);
    return motion;
  }
  if (static_cast<std::size_t>(pelvis) >= skeleton.jointCount())
    throw Error(fmt::format("{}: pelvis role: expected a joint index below {}, found {}", source,
                            skeleton.jointCount(), pelvis));

  const std::vector<int> path = pathTo(skeleton, pelvis);
  std::vector<int> children(skeleton.jointCount(), 0);
  for (std::size_t j = 1; j < skeleton.jointCount(); ++j) ++children[static_cast<std::size_t>(skeleton.joint(j).parent)];
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const std::size_t j = static_cast<std::size_t>(path[i]);
    if (children[j] != 1)
      throw Error(fmt::format(
          "{}: root motion: expected the joints above the pelvis role '{}' to lead only to it, found '{}' with {} "
          "children (they would move if the root motion moved down to '{}'); set the pelvis role to the file's "
          "root with roles: {{pelvis: {}}} to keep the file's root motion",
          source, skeleton.joint(static_cast<std::size_t>(pelvis)).name, skeleton.joint(j).name, children[j],
          skeleton.joint(static_cast<std::size_t>(pelvis)).name, skeleton.joint(0).name));
  }

  // The new skeleton: joint 0 animated in position and rotation, the path without offsets.
  std::vector<Joint> joints(skeleton.joints().begin(), skeleton.joints().end());
  Joint& root = joints[0];
  root.offset.setZero();
  if (!hasPositionChannel(root))
    root.channels.insert(root.channels.begin(), {{Channel::Kind::Position, Axis::X},
                                                 {Channel::Kind::Position, Axis::Y},
                                                 {Channel::Kind::Position, Axis::Z}});
  if (!hasRotationChannel(root))
    root.channels.insert(root.channels.end(), {{Channel::Kind::Rotation, Axis::Z},
                                               {Channel::Kind::Rotation, Axis::X},
                                               {Channel::Kind::Rotation, Axis::Y}});
  for (std::size_t i = 1; i < path.size(); ++i) joints[static_cast<std::size_t>(path[i])].offset.setZero();
  auto moved = std::make_shared<const Skeleton>(std::move(joints));

  const std::size_t jointCount = skeleton.jointCount(), frames = motion.frameCount();
  const std::size_t slots = moved->translatedJoints().size();
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  rotations.reserve(frames * jointCount);
  translations.reserve(frames * slots);
  std::vector<Eigen::Quaterniond> globalRotations(jointCount);
  std::vector<Eigen::Vector3d> globalPositions(jointCount);
  std::vector<char> onPath(jointCount, 0);
  for (const int j : path) onPath[static_cast<std::size_t>(j)] = 1;
  for (std::size_t f = 0; f < frames; ++f) {
    forwardKinematics(motion, f, globalRotations, globalPositions);
    const auto p = static_cast<std::size_t>(pelvis);
    for (std::size_t j = 0; j < jointCount; ++j)
      rotations.push_back(j == 0 ? globalRotations[p].normalized()
                                 : onPath[j] ? Eigen::Quaterniond::Identity() : motion.rotation(f, j));
    for (const int j : moved->translatedJoints()) {
      const auto u = static_cast<std::size_t>(j);
      translations.push_back(u == 0 ? globalPositions[p] : onPath[u] ? Eigen::Vector3d::Zero()
                                                                     : motion.localTranslation(f, u));
    }
  }
  report.joint = pelvis;
  report.jointName = skeleton.joint(static_cast<std::size_t>(pelvis)).name;
  // The same sentence when the motion already went through here (a cached graph's clips).
  report.sentence = fmt::format("root motion from '{}' (the pelvis role), not from the file's root '{}'",
                                report.jointName, skeleton.joint(0).name);
  return Motion(std::move(moved), motion.frameTime(), std::move(rotations), std::move(translations));
}

}  // namespace mgrl
