#pragma once
/// \file
/// Forward kinematics as one linear pass over parent-before-child joints into caller-owned
/// buffers (no allocation, no hidden cache), plus helpers built on it.

#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "mgrl/motion/motion.hpp"

namespace mgrl {

/// Global rotations and positions of every joint at `frame` of `motion`. Both spans must
/// have jointCount() elements. Root position is the root's local translation.
void forwardKinematics(const Motion& motion, std::size_t frame, std::span<Eigen::Quaterniond> rotations,
                       std::span<Eigen::Vector3d> positions);

/// The same pass over explicit local rotations and translations (one per joint), for poses
/// that are not frames of a Motion (rest pose, blended poses).
void forwardKinematics(const Skeleton& skeleton, std::span<const Eigen::Quaterniond> localRotations,
                       std::span<const Eigen::Vector3d> localTranslations, std::span<Eigen::Quaterniond> rotations,
                       std::span<Eigen::Vector3d> positions);

/// Joint `top` and every joint below it, in ascending order: what forwardKinematicsOf()
/// must redo after the local rotations of that subtree changed.
std::vector<int> subtreeJoints(const Skeleton& skeleton, int top);

/// The pass of forwardKinematics() for the listed joints only (ascending, as subtreeJoints()
/// gives them), whose parents outside the list are already up to date in `rotations` and
/// `positions`: after a change of a leg's local rotations, the leg alone is redone.
void forwardKinematicsOf(const Skeleton& skeleton, std::span<const int> joints,
                         std::span<const Eigen::Quaterniond> localRotations,
                         std::span<const Eigen::Vector3d> localTranslations, std::span<Eigen::Quaterniond> rotations,
                         std::span<Eigen::Vector3d> positions);

/// Joint positions for every frame, frame-major: result[f * jointCount + j].
std::vector<Eigen::Vector3d> jointPositions(const Motion& motion);

/// Rest-pose joint positions (identity rotations, offsets), root at its offset.
std::vector<Eigen::Vector3d> restPositions(const Skeleton& skeleton);

/// Velocities (units per second) from frame-major positions sampled every `frameTime`
/// seconds: central differences inside, one-sided at the ends, zero for a single frame.
std::vector<Eigen::Vector3d> velocities(std::span<const Eigen::Vector3d> positions, std::size_t pointCount,
                                        double frameTime);

/// Global position of a point given in the frame of joint `joint` (e.g. an end site).
inline Eigen::Vector3d pointOnJoint(std::span<const Eigen::Quaterniond> rotations,
                                    std::span<const Eigen::Vector3d> positions, std::size_t joint,
                                    const Eigen::Vector3d& local) {
  return positions[joint] + rotations[joint] * local;
}

/// Distance between the segments [p0, p1] and [q0, q1] (a point is a segment of zero
/// length): the body capsules' test, in the world and in bout statistics.
double segmentsDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                        const Eigen::Vector3d& q1);

}  // namespace mgrl
