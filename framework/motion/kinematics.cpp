#include "mgrl/motion/kinematics.hpp"

#include <cassert>

namespace mgrl {

void forwardKinematics(const Motion& motion, std::size_t frame, std::span<Eigen::Quaterniond> rotations,
                       std::span<Eigen::Vector3d> positions) {
  const Skeleton& skeleton = motion.skeleton();
  const std::size_t n = skeleton.jointCount();
  assert(rotations.size() >= n && positions.size() >= n);
  const auto local = motion.rotations(frame);
  const auto animated = motion.translations(frame);
  for (std::size_t j = 0; j < n; ++j) {
    const Joint& joint = skeleton.joint(j);
    const int slot = skeleton.translationSlot(j);
    const Eigen::Vector3d& t = slot < 0 ? joint.offset : animated[slot];
    if (joint.parent < 0) {
      rotations[j] = local[j];
      positions[j] = t;
    } else {
      assert(joint.parent < static_cast<int>(j));
      const auto p = static_cast<std::size_t>(joint.parent);
      rotations[j] = rotations[p] * local[j];
      positions[j] = positions[p] + rotations[p] * t;
    }
  }
}

namespace {

// Joint j's global rotation and position from its parent's (already computed) and its own
// local rotation and translation.
inline __attribute__((always_inline)) void jointKinematics(const Skeleton& skeleton, std::size_t j,
                                                           std::span<const Eigen::Quaterniond> localRotations,
                                                           std::span<const Eigen::Vector3d> localTranslations,
                                                           std::span<Eigen::Quaterniond> rotations,
                                                           std::span<Eigen::Vector3d> positions) {
  const int parent = skeleton.joint(j).parent;
  if (parent < 0) {
    rotations[j] = localRotations[j];
    positions[j] = localTranslations[j];
  } else {
    const auto p = static_cast<std::size_t>(parent);
    rotations[j] = rotations[p] * localRotations[j];
    positions[j] = positions[p] + rotations[p] * localTranslations[j];
  }
}

}  // namespace

void forwardKinematics(const Skeleton& skeleton, std::span<const Eigen::Quaterniond> localRotations,
                       std::span<const Eigen::Vector3d> localTranslations,
                       std::span<Eigen::Quaterniond> rotations, std::span<Eigen::Vector3d> positions) {
  const std::size_t n = skeleton.jointCount();
  assert(localRotations.size() >= n && localTranslations.size() >= n);
  for (std::size_t j = 0; j < n; ++j) jointKinematics(skeleton, j, localRotations, localTranslations, rotations, positions);
}

std::vector<int> subtreeJoints(const Skeleton& skeleton, int top) {
  const std::size_t n = skeleton.jointCount();
  if (top < 0 || static_cast<std::size_t>(top) >= n) return {};
  // Parents come before their children, so one pass in index order finds every descendant.
  std::vector<char> below(n, 0);
  std::vector<int> joints{top};
  below[static_cast<std::size_t>(top)] = 1;
  for (std::size_t j = static_cast<std::size_t>(top) + 1; j < n; ++j) {
    const int parent = skeleton.joint(j).parent;
    if (parent >= 0 && below[static_cast<std::size_t>(parent)]) {
      below[j] = 1;
      joints.push_back(static_cast<int>(j));
    }
  }
  return joints;
}

void forwardKinematicsOf(const Skeleton& skeleton, std::span<const int> joints,
                         std::span<const Eigen::Quaterniond> localRotations,
                         std::span<const Eigen::Vector3d> localTranslations, std::span<Eigen::Quaterniond> rotations,
                         std::span<Eigen::Vector3d> positions) {
  for (const int joint : joints)
    jointKinematics(skeleton, static_cast<std::size_t>(joint), localRotations, localTranslations, rotations, positions);
}

std::vector<Eigen::Vector3d> jointPositions(const Motion& motion) {
  const std::size_t n = motion.skeleton().jointCount();
  std::vector<Eigen::Vector3d> positions(motion.frameCount() * n);
  std::vector<Eigen::Quaterniond> rotations(n);
  for (std::size_t f = 0; f < motion.frameCount(); ++f)
    forwardKinematics(motion, f, rotations, std::span(positions).subspan(f * n, n));
  return positions;
}

std::vector<Eigen::Vector3d> restPositions(const Skeleton& skeleton) {
  const std::size_t n = skeleton.jointCount();
  std::vector<Eigen::Quaterniond> local(n, Eigen::Quaterniond::Identity()), global(n);
  std::vector<Eigen::Vector3d> offsets(n), positions(n);
  for (std::size_t j = 0; j < n; ++j) offsets[j] = skeleton.joint(j).offset;
  forwardKinematics(skeleton, local, offsets, global, positions);
  return positions;
}

std::vector<Eigen::Vector3d> velocities(std::span<const Eigen::Vector3d> positions, std::size_t pointCount,
                                        double frameTime) {
  const std::size_t frames = pointCount == 0 ? 0 : positions.size() / pointCount;
  std::vector<Eigen::Vector3d> result(positions.size(), Eigen::Vector3d::Zero());
  if (frames < 2) return result;
  for (std::size_t f = 0; f < frames; ++f) {
    const std::size_t before = f == 0 ? 0 : f - 1;
    const std::size_t after = f + 1 == frames ? f : f + 1;
    const double dt = static_cast<double>(after - before) * frameTime;
    for (std::size_t j = 0; j < pointCount; ++j)
      result[f * pointCount + j] = (positions[after * pointCount + j] - positions[before * pointCount + j]) / dt;
  }
  return result;
}

// Closest points by the clamped parameters of the two lines, then each re-clamped against
// the other's end.
double segmentsDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                        const Eigen::Vector3d& q1) {
  const Eigen::Vector3d u = p1 - p0, v = q1 - q0, w = p0 - q0;
  const double a = u.squaredNorm(), b = u.dot(v), c = v.squaredNorm(), d = u.dot(w), e = v.dot(w);
  const double det = a * c - b * b;
  double s = 0, t = 0;
  if (a < 1e-12 && c < 1e-12) return w.norm();
  if (a < 1e-12) {
    t = std::clamp(e / c, 0.0, 1.0);
  } else if (c < 1e-12) {
    s = std::clamp(-d / a, 0.0, 1.0);
  } else {
    s = det > 1e-12 * a * c ? std::clamp((b * e - c * d) / det, 0.0, 1.0) : 0.0;
    t = (b * s + e) / c;
    if (t < 0) {
      t = 0;
      s = std::clamp(-d / a, 0.0, 1.0);
    } else if (t > 1) {
      t = 1;
      s = std::clamp((b - d) / a, 0.0, 1.0);
    }
  }
  return (w + s * u - t * v).norm();
}

}  // namespace mgrl
