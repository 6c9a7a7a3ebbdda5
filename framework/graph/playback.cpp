#include "mgrl/graph/playback.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/motion/kinematics.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/core/rotation.hpp"

namespace mgrl {

namespace {

// Blend weight of the offset `b` frames into a transition: 1 on the first frame (the pose
// continues where it was), easing to 0 after `frames` frames.
double fade(int b, int frames) {
  if (b < 1 || b > frames) return 0;
  return 0.5 * (1 + std::cos(M_PI * (b - 1) / frames));
}

// Frame k of `clip` with the avatar factored out of its root (paper sec. 3: the avatar
// frame is the root's ground projection and yaw): the root's rotation without the yaw,
// its height above the ground and its ground offset from the avatar origin (x, z). The
// one place this is computed, so that the table (makeSourcePoses), the shown pose
// (sourceLocal) and a blended frame (next) agree bit for bit.
struct RootLocal {
  Eigen::Quaterniond tilt;
  double height;
  Eigen::Vector2d offset;
};
RootLocal rootLocal(const Clip& clip, std::size_t k) {
  const AvatarFrame& avatar = clip.annotation.frames[k];
  const Eigen::Vector3d root = clip.motion.localTranslation(k, 0);
  const Eigen::Vector3d local = avatar.toAvatar(root);
  return {axisRotation(Axis::Y, -avatar.yaw) * clip.motion.rotations(k)[0], root.y() - clip.annotation.groundY,
          {local.x(), local.z()}};
}

}  // namespace

ActionPlayback::ActionPlayback(const MotionDatabase& db, const StateActionModel& model, int blendFrames, bool lockFeet)
    : db_(db), model_(model), blendFrames_(std::max(0, blendFrames)), lockFeet_(lockFeet) {
  const std::size_t joints = db.skeleton->jointCount();
  current_.rotations.resize(joints);
  previous_.rotations.resize(joints);
  offset_.assign(joints, Eigen::Quaterniond::Identity());
  offsetHalfAngle_.assign(joints, 0.0);
  offsetAxis_.assign(joints, Eigen::Vector3d::UnitX());
  fkRotations_.resize(joints);
  fkPositions_.resize(joints);
  for (int side = 0; side < 2; ++side) {  // the leg chain above each ankle
    const int ankle = db.roles.ankle[static_cast<std::size_t>(side)];
    knee_[static_cast<std::size_t>(side)] = ankle > 0 ? db.skeleton->joint(static_cast<std::size_t>(ankle)).parent : -1;
    const int knee = knee_[static_cast<std::size_t>(side)];
    hip_[static_cast<std::size_t>(side)] = knee > 0 ? db.skeleton->joint(static_cast<std::size_t>(knee)).parent : -1;
    leg_[static_cast<std::size_t>(side)] = subtreeJoints(*db.skeleton, hip_[static_cast<std::size_t>(side)]);
  }
}

void ActionPlayback::sourceLocal(std::uint32_t frame, Local& out) const {
  const std::size_t c = db_.clipOf(frame);
  const Clip& clip = db_.clips[c];
  const std::size_t k = frame - db_.offsets[c];
  const auto rotations = clip.motion.rotations(k);
  std::copy(rotations.begin(), rotations.end(), out.rotations.begin());
  const RootLocal root = rootLocal(clip, k);
  out.rotations[0] = root.tilt;
  out.height = root.height;
  out.rootOffset = root.offset;
}

SourcePoses makeSourcePoses(const MotionDatabase& db) {
  const Skeleton& skeleton = *db.skeleton;
  const std::size_t joints = skeleton.jointCount();
  const std::size_t frames = db.frameCount();
  SourcePoses out;
  out.joints = joints;
  out.globals.resize(frames * joints);
  out.positions.resize(frames * joints);
  out.rootTilt.resize(frames);
  out.height.resize(frames);
  out.rootOffset.resize(frames);
  std::vector<Eigen::Quaterniond> rotations(joints);
  std::vector<Eigen::Vector3d> translations(joints);
  std::size_t v = 0;
  for (const Clip& clip : db.clips) {
    for (std::size_t k = 0; k < clip.motion.frameCount(); ++k, ++v) {
      // As sourceLocal() puts it: the root's yaw removed, its position apart.
      const auto local = clip.motion.rotations(k);
      std::copy(local.begin(), local.end(), rotations.begin());
      const RootLocal root = rootLocal(clip, k);
      rotations[0] = root.tilt;
      out.rootTilt[v] = root.tilt;
      out.height[v] = root.height;
      out.rootOffset[v] = root.offset;
      translations[0].setZero();
      for (std::size_t j = 1; j < joints; ++j) translations[j] = clip.motion.localTranslation(k, j);
      forwardKinematics(skeleton, rotations, translations, std::span(out.globals).subspan(v * joints, joints),
                        std::span(out.positions).subspan(v * joints, joints));
    }
  }
  return out;
}

void ActionPlayback::setSourcePoses(const SourcePoses* poses) {
  if (poses) {
    const std::size_t frames = db_.frameCount(), joints = db_.skeleton->jointCount();
    const bool fits = poses->joints == joints && poses->height.size() == frames && poses->rootTilt.size() == frames &&
                      poses->rootOffset.size() == frames && poses->globals.size() == frames * joints &&
                      poses->positions.size() == frames * joints;
    if (!fits)
      throw Error(fmt::format("playback: expected source poses of {} frames x {} joints, found {} x {} "
                              "({} global rotations, {} positions, {} root tilts, {} root offsets)",
                              frames, joints, poses->frameCount(), poses->joints, poses->globals.size(),
                              poses->positions.size(), poses->rootTilt.size(), poses->rootOffset.size()));
  }
  sourcePoses_ = poses;
}

// slerp(identity, offset, alpha) = (cos(alpha h), sin(alpha h) axis) for each joint's
// offset half angle h and axis, both found at the transition, applied to `rotations`.
void ActionPlayback::blend(double alpha, std::span<Eigen::Quaterniond> rotations) const {
  for (std::size_t j = 0; j < rotations.size(); ++j) {
    const double h = alpha * offsetHalfAngle_[j];
    const Eigen::Vector3d axis = std::sin(h) * offsetAxis_[j];
    rotations[j] = Eigen::Quaterniond(std::cos(h), axis.x(), axis.y(), axis.z()) * rotations[j];
  }
}

void ActionPlayback::refreshCurrent() {
  if (!currentStale_) return;
  currentStale_ = false;
  sourceLocal(frame_, current_);
  if (shownAlpha_ > 0) blend(shownAlpha_, current_.rotations);
  current_.height += shownAlpha_ * heightOffset_;
}

void ActionPlayback::reset(std::uint32_t state, const GroundMotion& world) {
  if (state >= model_.stateCount())
    throw Error(fmt::format("playback: expected a state below {}, found {}", model_.stateCount(), state));
  state_ = state;
  world_ = world;
  frame_ = model_.stateFrame[state];
  sourceLocal(frame_, current_);
  currentStale_ = false;
  std::fill(offset_.begin(), offset_.end(), Eigen::Quaterniond::Identity());
  std::fill(offsetHalfAngle_.begin(), offsetHalfAngle_.end(), 0.0);
  heightOffset_ = 0;
  sinceTransition_ = 1 << 30;
  correction_.setZero();
  havePrevious_ = false;
  held_ = {false, false};
  releasing_ = {1 << 30, 1 << 30};
}

void ActionPlayback::play(std::uint32_t action, std::vector<Pose>& out) {
  begin(action);
  Pose pose;
  while (next(pose)) out.push_back(pose);
}

void ActionPlayback::begin(std::uint32_t action) {
  if (action >= model_.actionCount() || model_.actionFrom[action] != state_)
    throw Error(fmt::format("playback: expected an action leaving state {}, found action {}", state_, action));
  action_ = action;
  cursor_ = model_.actionFrameBegin[action];
  end_ = model_.actionFrameBegin[action + 1];
}

bool ActionPlayback::next(Pose& pose) {
  if (cursor_ >= end_) return false;
  const Skeleton& skeleton = *db_.skeleton;
  const std::size_t joints = skeleton.jointCount();
  {
    const std::size_t i = cursor_++;
    const std::uint32_t v = model_.actionFrames[i];
    if (model_.frameEntersTransition[i]) {
      // The new clip expected frame v - 1 before v; the avatar shows `current_` instead.
      // Carry the difference as an offset that fades out (blending without a jump).
      refreshCurrent();
      sourceLocal(v - 1, previous_);
      for (std::size_t j = 0; j < joints; ++j) {
        offset_[j] = current_.rotations[j] * previous_.rotations[j].conjugate();
        if (offset_[j].w() < 0) offset_[j].coeffs() = -offset_[j].coeffs();
        const double sinHalf = offset_[j].vec().norm();
        offsetHalfAngle_[j] = std::atan2(sinHalf, offset_[j].w());
        offsetAxis_[j] = sinHalf > 1e-12 ? Eigen::Vector3d(offset_[j].vec() / sinHalf) : Eigen::Vector3d::UnitX();
      }
      heightOffset_ = current_.height - previous_.height;
      sinceTransition_ = 0;
    }
    ++sinceTransition_;
    const double alpha = fade(sinceTransition_, blendFrames_);
    const GroundMotion at = compose(world_, {model_.frameRoot[3 * i], model_.frameRoot[3 * i + 1], model_.frameRoot[3 * i + 2]});
    const Eigen::Quaterniond yaw = axisRotation(Axis::Y, at.dyaw);
    const std::size_t c = db_.clipOf(v);
    const std::size_t k = v - db_.offsets[c];
    const Motion& motion = db_.clips[c].motion;
    pose.rotations.resize(joints);
    // The skeleton's offsets unless the pose has them, then the joints with position
    // channels (the root's is set below).
    if (pose.translations.size() != joints || pose.offsetsOf != skeleton.id()) {
      pose.translations.resize(joints);
      std::copy(skeleton.offsets().begin(), skeleton.offsets().end(), pose.translations.begin());
      pose.offsetsOf = skeleton.id();
    }
    const auto translated = skeleton.translatedJoints();
    const auto moved = motion.translations(k);
    for (std::size_t t = 0; t < translated.size(); ++t) pose.translations[static_cast<std::size_t>(translated[t])] = moved[t];
    if (alpha == 0 && sourcePoses_) {
      // Outside a blend the pose is the source frame's: its kinematics were done once, and
      // only turn about the vertical and move with the avatar (the same as forward
      // kinematics below up to rounding).
      const auto local = motion.rotations(k);
      std::copy(local.begin(), local.end(), pose.rotations.begin());
      pose.rotations[0] = yaw * sourcePoses_->rootTilt[v];
      const Eigen::Vector2d& offset = sourcePoses_->rootOffset[v];
      const Eigen::Vector3d root = transformPoint(at, {offset.x(), sourcePoses_->height[v], offset.y()}) +
                                   Eigen::Vector3d(correction_.x(), 0, correction_.y());
      pose.translations[0] = root;
      const Eigen::Matrix3d turn = yaw.toRotationMatrix();
      const Eigen::Quaterniond* globals = sourcePoses_->globals.data() + std::size_t{v} * joints;
      const Eigen::Vector3d* positions = sourcePoses_->positions.data() + std::size_t{v} * joints;
      for (std::size_t j = 0; j < joints; ++j) {
        fkRotations_[j] = yaw * globals[j];
        fkPositions_[j] = root + turn * positions[j];
      }
    } else {
      // The source frame as sourceLocal() gives it, blended straight into the pose.
      const RootLocal root = rootLocal(db_.clips[c], k);
      const auto local = motion.rotations(k);
      pose.rotations[0] = root.tilt;
      std::copy(local.begin() + 1, local.end(), pose.rotations.begin() + 1);
      if (alpha > 0) blend(alpha, pose.rotations);
      pose.rotations[0] = yaw * pose.rotations[0];
      pose.translations[0] = transformPoint(at, {root.offset.x(), root.height + alpha * heightOffset_, root.offset.y()});
      pose.translations[0].x() += correction_.x();
      pose.translations[0].z() += correction_.y();
      forwardKinematics(skeleton, pose.rotations, pose.translations, fkRotations_, fkPositions_);
    }

    // While the offsets fade, the legs move against the root and a planted foot would
    // slide: shift the root so that feet planted in both this frame and the last stay put
    // (their mean drift is removed). The shift stays with the avatar.
    const std::array<bool, 2> down = {db_.clips[c].annotation.contact[0][k] != 0,
                                      db_.clips[c].annotation.contact[1][k] != 0};
    if (lockFeet_ && sinceTransition_ <= blendFrames_ && havePrevious_) {
      Eigen::Vector2d drift = Eigen::Vector2d::Zero();
      int planted = 0;
      for (int side = 0; side < 2; ++side) {
        if (!down[side] || !previousDown_[side]) continue;
        const Eigen::Vector3d d = fkPositions_[static_cast<std::size_t>(db_.roles.ankle[side])] - previousAnkle_[side];
        drift += Eigen::Vector2d(d.x(), d.z());
        ++planted;
      }
      if (planted) {
        drift /= planted;
        correction_ -= drift;
        pose.translations[0].x() -= drift.x();
        pose.translations[0].z() -= drift.y();
        for (auto& p : fkPositions_) {
          p.x() -= drift.x();
          p.z() -= drift.y();
        }
      }
    }
    if (footLock_) {
      // Each lock turns one leg only: redo the kinematics of that leg, not of the body.
      const auto& pivot = db_.clips[c].annotation.footPivot;
      const std::array<bool, 2> locked = {lockFoot(0, down[0], pivot[0][k], pose),
                                          lockFoot(1, down[1], pivot[1][k], pose)};
      for (int side = 0; side < 2; ++side)
        if (locked[side])
          forwardKinematicsOf(skeleton, leg_[static_cast<std::size_t>(side)], pose.rotations, pose.translations,
                              fkRotations_, fkPositions_);
    }
    for (int side = 0; side < 2; ++side) previousAnkle_[side] = fkPositions_[static_cast<std::size_t>(db_.roles.ankle[side])];
    previousDown_ = down;
    havePrevious_ = true;
    frame_ = v;
    // current_ is the blend at alpha of sourceLocal(v): computed when a transition needs it.
    currentStale_ = true;
    shownAlpha_ = alpha;
  }
  if (cursor_ == end_) {  // the action's last frame: the avatar stands at its end state
    world_ = compose(world_, model_.displacement(action_));
    world_.dx += correction_.x();
    world_.dz += correction_.y();
    correction_.setZero();
    state_ = model_.actionTo[action_];
  }
  return true;
}

Motion motionFromPoses(std::shared_ptr<const Skeleton> skeleton, const std::vector<Pose>& poses, double frameTime) {
  const std::size_t joints = skeleton->jointCount();
  const auto translated = skeleton->translatedJoints();
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  rotations.reserve(poses.size() * joints);
  translations.reserve(poses.size() * translated.size());
  for (const Pose& pose : poses) {
    if (pose.rotations.size() != joints || pose.translations.size() != joints)
      throw Error(fmt::format("poses: expected {} joints per pose, found {}", joints, pose.rotations.size()));
    rotations.insert(rotations.end(), pose.rotations.begin(), pose.rotations.end());
    for (int j : translated) translations.push_back(pose.translations[static_cast<std::size_t>(j)]);
  }
  return Motion(std::move(skeleton), frameTime, std::move(rotations), std::move(translations));
}

}  // namespace mgrl
