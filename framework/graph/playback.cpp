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

// Frames over which a lifted foot goes from where it was held back to the motion's.
constexpr int kRelease = 4;

// How far a held foot's heading may stay behind the motion's before the foot pivots about
// the point it rests on (radians): within the hip's range of inward and outward rotation (about 40 degrees
// each way in adults), with room for the motion's own.
constexpr double kMaxFootTwist = 25 * M_PI / 180;
const double kMaxHalfTwistSin = std::sin(0.5 * kMaxFootTwist);

// A held foot keeps half of the motion's change of pitch and roll since it landed (the rest
// is the landing's): the rotation halfway between the two. The CMU boxer's feet roll and
// twist on the floor far more than fighters' do: with all of it, its planted ankles moved
// 0.13 to 0.16 m/s about the held ball against the SNU sparring capture's 0.078; with half,
// 0.07 to 0.09, the toes 0.02 to 0.03 (the SNU's: 0.029); with 0.3, 0.05 to 0.07 and 0.01
// to 0.02. Issue 46, measured with mgrl stats on 120 s bouts. Halfway is slerp at 1/2,
// which is the normalized sum of the two (no acos or sine in the posing loop).
Eigen::Quaterniond halfway(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const double sign = a.coeffs().dot(b.coeffs()) < 0 ? -1.0 : 1.0;
  return Eigen::Quaterniond((a.coeffs() + sign * b.coeffs()).normalized());
}

// The foot's heading as its global rotation's twist about the vertical (the swing-twist
// split): the unit (w, y) of a rotation about y, defined whatever the foot's pitch and roll
// (a toe pointing down has no horizontal direction, but its rotation still has a twist).
// Kept as half-angle cosine and sine, so holding a heading needs no atan2, sine or cosine.
Eigen::Vector2d twistAboutVertical(const Eigen::Quaterniond& q) {
  const Eigen::Vector2d t(q.w(), q.y());
  const double n = t.norm();
  return n > 1e-12 ? Eigen::Vector2d(t / n) : Eigen::Vector2d(1, 0);
}

// The rotation about y from twist `from` to twist `to`, its w made non-negative (the
// shorter way round: an angle in [-pi, pi]).
Eigen::Vector2d twistBetween(const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
  const Eigen::Vector2d r(to.x() * from.x() + to.y() * from.y(), to.y() * from.x() - to.x() * from.y());
  return r.x() < 0 ? Eigen::Vector2d(-r) : r;
}

// Twist `b` after twist `a` (both rotations about y).
Eigen::Vector2d twistAfter(const Eigen::Vector2d& b, const Eigen::Vector2d& a) {
  return {b.x() * a.x() - b.y() * a.y(), b.y() * a.x() + b.x() * a.y()};
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
      const auto& pivots = db_.clips[c].annotation.footPivot;
      auto pivot = [&](int side) {  // 0.5 (flat) for an annotation made without it
        const auto& p = pivots[static_cast<std::size_t>(side)];
        return k < p.size() ? double(p[k]) : 0.5;
      };
      const std::array<bool, 2> locked = {lockFoot(0, down[0], pivot(0), pose), lockFoot(1, down[1], pivot(1), pose)};
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

// Holds foot `side` (issues 18 and 46): the whole foot, not the ankle alone. A foot that
// comes down is held at its heading (its twist about the vertical) and its pitch and roll
// move only half of the way the motion's do (halfway()); the point it rests on (the motion's
// Annotation::footPivot, `pivot`: heel, ball or between) stays where it was on the floor
// and keeps the motion's height, and the ankle goes where that foot puts it. So a heel
// that rises turns the foot about the ball, as fighters stand: the SNU sparring capture's
// planted toes move 0.029 m/s, its ankles 0.078 (with the ankle alone held, the toes swept
// about it at 0.24 m/s as the body turned). Hip and knee turn so the ankle reaches its
// target (two-bone IK: the knee's angle by the law of cosines, about the leg's bending
// axis, then the hip turns the leg onto the target), and the leg turns about the hip-ankle
// line as much as the foot's heading was turned back, as a hip rotates, so the knee keeps
// pointing over the foot. A body that turns the foot more than kMaxFootTwist away from the
// motion's heading pivots it. Once lifted, position and rotation fade into the motion's
// over kRelease frames. A skeleton without a toe joint rests on the ankle. Rotations only,
// so bone lengths never change. Uses and updates fkRotations_ / fkPositions_ of the leg
// only; returns whether it turned the leg, and then the caller redoes forward kinematics.
bool ActionPlayback::lockFoot(int side, bool down, double pivot, Pose& pose) {
  const auto s = static_cast<std::size_t>(side);
  const int ankleJoint = db_.roles.ankle[s], kneeJoint = knee_[s], hipJoint = hip_[s], toeJoint = db_.roles.toe[s];
  if (ankleJoint <= 0 || kneeJoint <= 0 || hipJoint <= 0) return false;
  const auto a = static_cast<std::size_t>(ankleJoint), k = static_cast<std::size_t>(kneeJoint),
             h = static_cast<std::size_t>(hipJoint);
  const Eigen::Vector3d ankle = fkPositions_[a];
  const Eigen::Quaterniond& footNow = fkRotations_[a];
  // The ball in the foot's own frame (from the ankle), as the motion has it.
  const Eigen::Vector3d ball = toeJoint > 0 ? fkPositions_[static_cast<std::size_t>(toeJoint)] : ankle;
  const Eigen::Vector3d footLocal = footNow.conjugate() * (ball - ankle);
  const Eigen::Vector2d heading = twistAboutVertical(footNow);
  double weight = 1;
  if (down) {
    if (!held_[s]) {
      anchor_[s] = ankle;
      anchorHeading_[s] = heading;
      heldRotation_[s] = footNow;
      heldFoot_[s] = Eigen::Vector2d(ball.x() - ankle.x(), ball.z() - ankle.z());
    }
    held_[s] = true;
    releasing_[s] = 1 << 30;
  } else {
    if (held_[s]) releasing_[s] = 0;
    held_[s] = false;
    if (releasing_[s] >= kRelease) return false;
    ++releasing_[s];
    weight = 0.5 * (1 + std::cos(M_PI * releasing_[s] / (kRelease + 1)));
  }
  // What turns the foot back to its held heading, as (cos, sin) of half its angle.
  Eigen::Vector2d turn = twistBetween(heading, anchorHeading_[s]);
  if (held_[s] && std::abs(turn.y()) > kMaxHalfTwistSin) {  // the body turned the foot: it pivots
    const Eigen::Vector2d limit(std::sqrt(1 - kMaxHalfTwistSin * kMaxHalfTwistSin),
                                std::copysign(kMaxHalfTwistSin, turn.y()));
    const Eigen::Vector2d excess = twistBetween(turn, limit);  // turns the held foot onto the limit
    anchorHeading_[s] = twistAfter(excess, anchorHeading_[s]);
    heldRotation_[s] = Eigen::Quaterniond(excess.x(), 0, excess.y(), 0) * heldRotation_[s];
    turn = limit;
  }
  // The held foot: the motion's at the held heading, its pitch and roll moved half of the
  // way from the landing's.
  const double halfCos = turn.x(), halfSin = turn.y();
  const Eigen::Quaterniond turned = Eigen::Quaterniond(halfCos, 0, halfSin, 0) * footNow;
  const Eigen::Quaterniond heldFoot = halfway(heldRotation_[s], turned);
  const Eigen::Vector3d heldBall = heldFoot * footLocal;  // from the ankle
  // The resting point keeps the motion's height and stays where the last frame's held
  // foot had it on the floor.
  double ankleY = ankle.y() + pivot * ((ball.y() - ankle.y()) - heldBall.y());
  if (held_[s]) {
    const Eigen::Vector2d now(heldBall.x(), heldBall.z());
    const Eigen::Vector2d shift = pivot * (heldFoot_[s] - now);
    anchor_[s].x() += shift.x();
    anchor_[s].z() += shift.y();
    heldFoot_[s] = now;
    lastAnkleY_[s] = ankleY - ankle.y();
  } else {
    ankleY = ankle.y() + lastAnkleY_[s];
  }
  const Eigen::Quaterniond footGlobal = weight == 1 ? heldFoot : footNow.slerp(weight, heldFoot);
  const Eigen::Vector3d target = ankle + weight * (Eigen::Vector3d(anchor_[s].x(), ankleY, anchor_[s].z()) - ankle);
  const Eigen::Vector3d hip = fkPositions_[h], knee = fkPositions_[k];
  const double upper = (knee - hip).norm(), lower = (ankle - knee).norm();
  if (upper < 1e-6 || lower < 1e-6) return false;
  if ((target - hip).norm() > 0.995 * (upper + lower)) {  // out of reach: plant it again here
    if (held_[s]) {
      anchor_[s] = ankle;
      anchorHeading_[s] = heading;
      heldRotation_[s] = footNow;
      heldFoot_[s] = Eigen::Vector2d(ball.x() - ankle.x(), ball.z() - ankle.z());
    }
    return false;
  }
  const bool moves = (target - ankle).squaredNorm() >= 1e-10;
  if (!held_[s] && !moves && footGlobal.angularDistance(footNow) < 1e-9) return false;
  Eigen::Quaterniond hipGlobal = fkRotations_[h], kneeGlobal = fkRotations_[k];
  if (moves) {
    const double reach = std::clamp((target - hip).norm(), std::abs(upper - lower) + 1e-6, upper + lower - 1e-6);
    // The knee: from its current angle to the one that puts the ankle `reach` from the hip.
    const Eigen::Vector3d toHip = (hip - knee) / upper, toAnkle = (ankle - knee) / lower;
    Eigen::Vector3d axis = toHip.cross(toAnkle);
    if (axis.norm() < 1e-6)
      axis = fkRotations_[k] * Eigen::Vector3d::UnitX();  // a straight leg bends about the knee's x
    axis.normalize();
    const double now = std::acos(std::clamp(toHip.dot(toAnkle), -1.0, 1.0));
    const double wanted =
        std::acos(std::clamp((upper * upper + lower * lower - reach * reach) / (2 * upper * lower), -1.0, 1.0));
    const Eigen::Quaterniond bend(Eigen::AngleAxisd(wanted - now, axis));
    const Eigen::Vector3d bentAnkle = knee + bend * (ankle - knee);
    // The hip: turn the leg so the ankle lies on the target.
    const Eigen::Quaterniond swing = Eigen::Quaterniond::FromTwoVectors(bentAnkle - hip, target - hip);
    hipGlobal = swing * hipGlobal;
    kneeGlobal = swing * bend * kneeGlobal;
  }
  // The leg turns with the foot's heading about the hip-ankle line (the ankle stays on the
  // target), so the knee keeps pointing over the foot.
  if (halfSin != 0) {
    const Eigen::Vector3d line = (target - hip).normalized();
    const Eigen::Quaterniond roll =
        weight == 1 ? Eigen::Quaterniond(halfCos, halfSin * line.x(), halfSin * line.y(), halfSin * line.z())
                    : Eigen::Quaterniond(Eigen::AngleAxisd(weight * 2 * std::atan2(halfSin, halfCos), line));
    hipGlobal = roll * hipGlobal;
    kneeGlobal = roll * kneeGlobal;
  }
  const Skeleton& skeleton = *db_.skeleton;
  const int hipParent = skeleton.joint(h).parent;
  const Eigen::Quaterniond parentGlobal =
      hipParent >= 0 ? fkRotations_[static_cast<std::size_t>(hipParent)] : Eigen::Quaterniond::Identity();
  pose.rotations[h] = (parentGlobal.conjugate() * hipGlobal).normalized();
  pose.rotations[k] = (hipGlobal.conjugate() * kneeGlobal).normalized();
  pose.rotations[a] = (kneeGlobal.conjugate() * footGlobal).normalized();
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
