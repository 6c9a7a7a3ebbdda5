/// \file
/// checkPlayback(): a seeded random walk played with blending, measured against the source
/// capture (foot sliding, joint steps). Its own file: a measurement of playback, which
/// `mgrl graph` reports, not part of it.
#include "mgrl/graph/playback.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "mgrl/motion/kinematics.hpp"

namespace mgrl {

namespace {

// Adds the horizontal ankle motion between two frames to `slide` if both have the foot down.
void addSlide(const SkeletonRoles& roles, std::span<const Eigen::Vector3d> a, std::span<const Eigen::Vector3d> b,
              const std::array<bool, 2>& downA, const std::array<bool, 2>& downB, double dt, double& sum,
              std::size_t& pairs) {
  for (int s = 0; s < 2; ++s) {
    if (!downA[s] || !downB[s]) continue;
    const std::size_t ankle = static_cast<std::size_t>(roles.ankle[s]);
    const Eigen::Vector3d d = b[ankle] - a[ankle];
    sum += std::hypot(d.x(), d.z()) / dt;
    ++pairs;
  }
}

std::array<bool, 2> footDown(const MotionDatabase& db, std::uint32_t frame) {
  const std::size_t c = db.clipOf(frame);
  const std::size_t k = frame - db.offsets[c];
  return {db.clips[c].annotation.contact[0][k] != 0, db.clips[c].annotation.contact[1][k] != 0};
}

}  // namespace

PlaybackCheck checkPlayback(const MotionDatabase& db, const StateActionModel& model, int blendFrames,
                            std::size_t actions, std::uint64_t seed) {
  PlaybackCheck check;
  const Skeleton& skeleton = *db.skeleton;
  const std::size_t joints = skeleton.jointCount();
  // One pass over the capture: each joint's largest step, each frame's ankle speed from
  // its predecessor (0 for a clip's first frame: the baseline for the same frames played),
  // and the capture's own foot sliding.
  std::vector<double> sourceStep(joints, 0);
  std::vector<std::array<double, 2>> sourceAnkleSpeed(db.frameCount(), {0.0, 0.0});
  double captureSum = 0;
  for (std::size_t c = 0; c < db.clips.size(); ++c) {
    const std::vector<Eigen::Vector3d> p = jointPositions(db.clips[c].motion);
    for (std::size_t k = 1; k < db.clips[c].motion.frameCount(); ++k) {
      for (std::size_t j = 0; j < joints; ++j)
        sourceStep[j] = std::max(sourceStep[j], (p[k * joints + j] - p[(k - 1) * joints + j]).norm());
      const auto g = static_cast<std::uint32_t>(db.offsets[c] + k);
      for (int side = 0; side < 2; ++side) {
        const std::size_t ankle = static_cast<std::size_t>(db.roles.ankle[side]);
        const Eigen::Vector3d d = p[k * joints + ankle] - p[(k - 1) * joints + ankle];
        sourceAnkleSpeed[g][side] = std::hypot(d.x(), d.z()) / db.frameTime;
      }
      addSlide(db.roles, {p.data() + (k - 1) * joints, joints}, {p.data() + k * joints, joints}, footDown(db, g - 1),
               footDown(db, g), db.frameTime, captureSum, check.captureSlide.framePairs);
    }
  }
  check.captureSlide.meanSpeed_mps =
      captureSum / static_cast<double>(std::max<std::size_t>(check.captureSlide.framePairs, 1));
  check.sourceMaxJointStep_m = *std::max_element(sourceStep.begin(), sourceStep.end());
  double sourceSum = 0;

  std::mt19937_64 rng(seed);
  ActionPlayback playback(db, model, blendFrames);
  playback.reset(static_cast<std::uint32_t>(rng() % model.stateCount()));
  std::vector<Pose> poses;
  std::vector<Eigen::Quaterniond> rot(joints);
  std::vector<Eigen::Vector3d> pos(joints), last(joints);
  bool haveLast = false;
  std::uint32_t lastFrame = 0;
  double slideSum = 0;
  for (std::size_t n = 0; n < actions; ++n) {
    const std::uint32_t s = playback.state();
    const std::uint32_t count = model.stateActionBegin[s + 1] - model.stateActionBegin[s];
    const std::uint32_t a = model.stateActionBegin[s] + static_cast<std::uint32_t>(rng() % count);
    const std::size_t begin = model.actionFrameBegin[a];
    poses.clear();
    playback.play(a, poses);
    ++check.actions;
    check.transitions += model.frameEntersTransition[begin];
    for (std::size_t i = 0; i < poses.size(); ++i) {
      forwardKinematics(skeleton, poses[i].rotations, poses[i].translations, rot, pos);
      const std::uint32_t v = model.actionFrames[begin + i];
      if (haveLast) {
        for (std::size_t j = 0; j < joints; ++j) {
          const double step = (pos[j] - last[j]).norm();
          check.maxJointStep_m = std::max(check.maxJointStep_m, step);
          if (sourceStep[j] > 0 && step / sourceStep[j] > check.worstJointStepRatio) {
            check.worstJointStepRatio = step / sourceStep[j];
            check.worstJoint = static_cast<int>(j);
          }
        }
        const std::array<bool, 2> before = footDown(db, lastFrame), now = footDown(db, v);
        addSlide(db.roles, last, pos, before, now, db.frameTime, slideSum, check.slide.framePairs);
        for (int side = 0; side < 2; ++side)
          if (before[side] && now[side]) sourceSum += sourceAnkleSpeed[v][side];
      }
      last = pos;
      lastFrame = v;
      haveLast = true;
      ++check.frames;
    }
  }
  const double pairs = static_cast<double>(std::max<std::size_t>(check.slide.framePairs, 1));
  check.slide.meanSpeed_mps = slideSum / pairs;
  check.sourceSlideSameFrames_mps = sourceSum / pairs;
  return check;
}

}  // namespace mgrl
