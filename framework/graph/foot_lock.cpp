/// \file
/// Planted feet for ActionPlayback: ActionPlayback::lockFoot, the whole
/// foot held by two-bone IK while the annotation has it on the ground. Its own file because
/// it changes for other reasons than playback's blending and posing (motion quality).
#include "mgrl/graph/playback.hpp"

#include <algorithm>
#include <cmath>

namespace mgrl {

namespace {

// Frames over which a lifted foot goes from where it was held back to the motion's.
constexpr int kRelease = 4;

// How far a held foot's heading may stay behind the motion's before the foot pivots about
// the point it rests on (radians): within the hip's range of inward and outward rotation
// (about 40 degrees each way in adults), with room for the motion's own.
constexpr double kMaxFootTwist = 25 * M_PI / 180;
const double kMaxHalfTwistSin = std::sin(0.5 * kMaxFootTwist);

// A held foot keeps half of the motion's change of pitch and roll since it landed (the rest
// is the landing's): the rotation halfway between the two. The CMU boxer's feet roll and
// twist on the floor far more than fighters' do: with all of it, its planted ankles moved
// 0.13 to 0.16 m/s about the held ball against the SNU sparring capture's 0.078; with half,
// 0.07 to 0.09, the toes 0.02 to 0.03 (the SNU's: 0.029); with 0.3, 0.05 to 0.07 and 0.01
// to 0.02. Measured with mgrl stats on 120 s bouts. Halfway is slerp at 1/2,
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

}  // namespace

// Holds foot `side`: the whole foot, not the ankle alone. A foot that
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
  auto plant = [&] {  // hold the foot as the motion has it now
    anchor_[s] = ankle;
    anchorHeading_[s] = heading;
    heldRotation_[s] = footNow;
    lastHeldBall_[s] = Eigen::Vector2d(ball.x() - ankle.x(), ball.z() - ankle.z());
  };
  double weight = 1;
  if (down) {
    if (!held_[s]) plant();
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
    const Eigen::Vector2d shift = pivot * (lastHeldBall_[s] - now);
    anchor_[s].x() += shift.x();
    anchor_[s].z() += shift.y();
    lastHeldBall_[s] = now;
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
    if (held_[s]) plant();
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

}  // namespace mgrl
