#include "mgrl/motion/annotation.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/kinematics.hpp"

namespace mgrl {
namespace {

// Index of the q-quantile among n sorted values.
std::size_t quantileIndex(std::size_t n, double q) { return static_cast<std::size_t>(q * static_cast<double>(n - 1)); }

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const std::size_t k = quantileIndex(values.size(), q);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

void AnnotationParams::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v)) throw Error(fmt::format("annotation: {}: expected a positive value, found {}", name, v));
  };
  positive(contactHeightEnter_m, "contact_height_enter_m");
  positive(contactHeightExit_m, "contact_height_exit_m");
  positive(contactSpeedEnter_mps, "contact_speed_enter_mps");
  positive(contactSpeedExit_mps, "contact_speed_exit_mps");
  positive(punchMinSpeed_mps, "punch_min_speed_mps");
  positive(punchMaxSpeed_mps, "punch_max_speed_mps");
  if (contactHeightExit_m < contactHeightEnter_m || contactSpeedExit_mps < contactSpeedEnter_mps)
    throw Error("annotation: expected exit thresholds at least the enter thresholds (hysteresis), found smaller");
  if (!(punchMinAlignment >= 0 && punchMinAlignment <= 1))
    throw Error(fmt::format("annotation: punch_min_alignment: expected a value in [0, 1], found {}", punchMinAlignment));
  if (!(punchMinBodySpeed_mps >= 0 && punchMinBodySpeed_mps <= 100))
    throw Error(fmt::format("annotation: punch_min_body_speed_mps: expected a speed in [0, 100] m/s (0: off), found {}",
                            punchMinBodySpeed_mps));
  if (!(swingTravel_mps >= 0 && swingTravel_mps <= 20))
    throw Error(fmt::format("annotation: swing_travel_mps: expected a speed in [0, 20] m/s (0: off), found {}",
                            swingTravel_mps));
  if (!(swingMaxReach_mps >= 0 && swingMaxReach_mps <= 100))
    throw Error(
        fmt::format("annotation: swing_max_reach_mps: expected a speed in [0, 100] m/s, found {}", swingMaxReach_mps));
  if (!(knockdownHeadRatio >= 0 && knockdownHeadRatio < 1))
    throw Error(fmt::format("annotation: knockdown_head_ratio: expected a value in [0, 1) (0: off), found {}",
                            knockdownHeadRatio));
  positive(kickMinSpeed_mps, "kick_min_speed_mps");
  positive(kickMaxSpeed_mps, "kick_max_speed_mps");
  if (!(kickMinAlignment >= 0 && kickMinAlignment <= 1))
    throw Error(fmt::format("annotation: kick_min_alignment: expected a value in [0, 1], found {}", kickMinAlignment));
  if (!(kickMinHeight_m >= 0 && kickMinHeight_m <= 3))
    throw Error(fmt::format("annotation: kick_min_height_m: expected a height in [0, 3] m, found {}", kickMinHeight_m));
  if (kickMaxSpeed_mps <= kickMinSpeed_mps)
    throw Error(fmt::format("annotation: kick_max_speed_mps: expected a value above kick_min_speed_mps ({}), found {}",
                            kickMinSpeed_mps, kickMaxSpeed_mps));
  if (punchMaxSpeed_mps <= punchMinSpeed_mps)
    throw Error(fmt::format("annotation: punch_max_speed_mps: expected a value above punch_min_speed_mps ({}), found {}",
                            punchMinSpeed_mps, punchMaxSpeed_mps));
}

Eigen::Vector3d AvatarFrame::toAvatar(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d d = world - origin;
  const double c = std::cos(yaw), s = std::sin(yaw);
  // Rotation by -yaw about +Y.
  return {c * d.x() - s * d.z(), d.y(), s * d.x() + c * d.z()};
}

std::size_t Annotation::contactFrames(Side side) const {
  const auto& c = contact[static_cast<int>(side)];
  return static_cast<std::size_t>(std::count(c.begin(), c.end(), 1));
}

std::size_t Annotation::hitCount(Side side) const {
  return static_cast<std::size_t>(std::count_if(hits.begin(), hits.end(), [side](const EffectiveHit& h) { return h.hand == side; }));
}

namespace {

// The points annotate() follows, per frame (kPoints of them; see trackPoints()), their
// velocities, and the root's position and facing.
struct Tracked {
  static constexpr std::size_t kPoints = 17;
  std::size_t frames = 0;
  double frameTime = 0;
  std::vector<Eigen::Vector3d> points, velocity, rootPosition, facing;
  std::vector<Eigen::Vector3d> pelvis;  // the pelvis role's joint (the root, once moved there)
};

// Tracked points per frame: ankle L/R, toe L/R, fist tip L/R, wrist L/R, forearm L/R,
// toe tip L/R, head top, knee L/R (the ankle's parent), shoulder L/R.
Tracked trackPoints(const Motion& motion, const SkeletonRoles& roles) {
  const Skeleton& skeleton = motion.skeleton();
  const std::size_t frames = motion.frameCount();
  const std::size_t n = skeleton.jointCount();
  constexpr std::size_t kPoints = Tracked::kPoints;
  Tracked t;
  t.frames = frames;
  t.frameTime = motion.frameTime();
  std::vector<Eigen::Vector3d> points(frames * kPoints);
  std::vector<Eigen::Vector3d> rootPosition(frames), facing(frames), pelvis(frames);
  std::vector<Eigen::Quaterniond> rotations(n);
  std::vector<Eigen::Vector3d> positions(n);
  for (std::size_t f = 0; f < frames; ++f) {
    forwardKinematics(motion, f, rotations, positions);
    Eigen::Vector3d* p = &points[f * kPoints];
    for (int s = 0; s < 2; ++s) {
      p[0 + s] = positions[roles.ankle[s]];
      p[2 + s] = positions[roles.toe[s]];
      p[4 + s] = pointOnJoint(rotations, positions, roles.fistTipJoint[s], roles.fistTipOffset[s]);
      p[6 + s] = positions[roles.wrist[s]];
      p[8 + s] = positions[roles.forearm[s]];
      p[10 + s] = pointOnJoint(rotations, positions, roles.toe[s], roles.toeTipOffset[s]);
    }
    p[12] = pointOnJoint(rotations, positions, roles.head, roles.headTopOffset);
    for (int s = 0; s < 2; ++s) {
      const int knee = skeleton.joint(static_cast<std::size_t>(roles.ankle[s])).parent;
      p[13 + s] = positions[knee >= 0 ? knee : roles.ankle[s]];
      p[15 + s] = positions[roles.shoulder[s]];
    }
    rootPosition[f] = positions[0];
    pelvis[f] = positions[static_cast<std::size_t>(roles.pelvis >= 0 ? roles.pelvis : 0)];
    facing[f] = rotations[0] * roles.forward;
  }
  t.velocity = velocities(points, kPoints, motion.frameTime());
  t.points = std::move(points);
  t.rootPosition = std::move(rootPosition);
  t.facing = std::move(facing);
  t.pelvis = std::move(pelvis);
  return t;
}

// The ground, foot contacts and where each planted foot rests; returns each frame's lowest
// foot point.
std::vector<double> findContacts(const Tracked& t, const AnnotationParams& params, Annotation& result) {
  const std::size_t frames = t.frames;
  constexpr std::size_t kPoints = Tracked::kPoints;
  const std::vector<Eigen::Vector3d>& points = t.points;
  const std::vector<Eigen::Vector3d>& velocity = t.velocity;
  // Planted level of each foot joint at each frame: the height it rests at when down
  // nearby in time (10th percentile within +-1 s). Local, because capture floors tilt and
  // drift (CMU 07_05 rises 5 cm over its 4 m walk); a percentile, because some frames dip
  // through the floor (SNU s_019_2_1).
  const std::size_t window = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(1.0 / t.frameTime)));
  std::array<std::vector<double>, 4> planted;
  std::vector<double> heights(frames), lowest(frames);
  for (std::size_t k = 0; k < 4; ++k) {
    for (std::size_t f = 0; f < frames; ++f) heights[f] = points[f * kPoints + k].y();
    planted[k] = windowQuantiles(heights, window, 0.10);
  }
  for (std::size_t f = 0; f < frames; ++f) {
    double low = 1e300;
    for (std::size_t k : {0, 1, 2, 3, 10, 11}) low = std::min(low, points[f * kPoints + k].y());
    lowest[f] = low;
  }
  result.groundY = percentile(lowest, 0.10);

  // Foot contacts with hysteresis: a foot enters contact when its ankle or toe is low and
  // slow by the enter thresholds, and stays until both leave the exit thresholds.
  for (int s = 0; s < 2; ++s) {
    auto& contact = result.contact[s];
    contact.assign(frames, 0);
    bool on = false;
    for (std::size_t f = 0; f < frames; ++f) {
      auto near = [&](std::size_t k, double height, double speed) {
        const std::size_t i = f * kPoints + k;
        return points[i].y() - planted[k][f] < height && velocity[i].norm() < speed;
      };
      const std::size_t ankle = static_cast<std::size_t>(s), toe = 2 + static_cast<std::size_t>(s);
      if (on)
        on = near(ankle, params.contactHeightExit_m, params.contactSpeedExit_mps) ||
             near(toe, params.contactHeightExit_m, params.contactSpeedExit_mps);
      else
        on = near(ankle, params.contactHeightEnter_m, params.contactSpeedEnter_mps) ||
             near(toe, params.contactHeightEnter_m, params.contactSpeedEnter_mps);
      contact[f] = on ? 1 : 0;
    }
    // Where the foot rests: on its heel or its ball, by which of ankle and toe stands
    // higher above its own planted level (playback holds that point still).
    auto& pivot = result.footPivot[s];
    pivot.resize(frames);
    const std::size_t ankle = static_cast<std::size_t>(s), toe = 2 + static_cast<std::size_t>(s);
    for (std::size_t f = 0; f < frames; ++f) {
      const double heelRise = points[f * kPoints + ankle].y() - planted[ankle][f];
      const double ballRise = points[f * kPoints + toe].y() - planted[toe][f];
      pivot[f] = static_cast<float>(std::clamp(0.5 + 0.5 * (heelRise - ballRise) / kPivotRise_m, 0.0, 1.0));
    }
  }

  return lowest;
}

// Standing height from the motion; returns the head top's height above the lower foot,
// per frame.
std::vector<double> measureStanding(const Tracked& t, const std::vector<double>& lowest, Annotation& result) {
  const std::size_t frames = t.frames;
  constexpr std::size_t kPoints = Tracked::kPoints;
  const std::vector<Eigen::Vector3d>& points = t.points;
  // Standing height from the motion: the head top above the lower foot while both feet
  // are down. A high percentile, because boxers stand in a crouch most of the time.
  std::vector<double> headAbove(frames), standing;
  for (std::size_t f = 0; f < frames; ++f) headAbove[f] = points[f * kPoints + 12].y() - lowest[f];
  for (int needed : {2, 1, 0}) {
    standing.clear();
    for (std::size_t f = 0; f < frames; ++f)
      if (result.contact[0][f] + result.contact[1][f] >= needed) standing.push_back(headAbove[f]);
    if (!standing.empty()) break;
  }
  result.standingFrames = standing.size();
  result.standingHeight = percentile(standing, 0.99);

  return headAbove;
}

// How fast the body travels around frame f: the pelvis's net ground displacement over
// kSwingTravelWindow_s centred on f (clamped to the clip), per second. Walking and running
// keep it up for seconds; a fighter's step in or out does not.
constexpr double kSwingTravelWindow_s = 3.0;
double travelAround(const Tracked& t, std::size_t f) {
  const auto half = static_cast<std::size_t>(std::lround(0.5 * kSwingTravelWindow_s / t.frameTime));
  const std::size_t a = f > half ? f - half : 0;
  const std::size_t b = std::min(t.frames - 1, f + half);
  if (b <= a) return 0;
  Eigen::Vector3d d = t.pelvis[b] - t.pelvis[a];
  d.y() = 0;
  return d.norm() / (static_cast<double>(b - a) * t.frameTime);
}

void findPunches(const Tracked& t, const Skeleton& skeleton, const SkeletonRoles& roles, const AnnotationParams& params,
                 const std::vector<double>& headAbove, Annotation& result) {
  const std::size_t frames = t.frames;
  constexpr std::size_t kPoints = Tracked::kPoints;
  const std::vector<Eigen::Vector3d>& points = t.points;
  const std::vector<Eigen::Vector3d>& velocity = t.velocity;
  const std::vector<Eigen::Vector3d>& rootPosition = t.rootPosition;
  const double knockdownBelow = params.knockdownHeadRatio * result.standingHeight;
  // Effective punches (sec. 6.2): fist velocity projected on the forearm axis above a
  // threshold, and not opposed to it, by a boxer on his feet. Then each punch (a run of
  // such frames of one hand) must drive the fist out from the body: at one of its frames at
  // least, the fist's velocity relative to the pelvis, along the forearm, reaches
  // punchMinBodySpeed_mps. An arm swinging while the body walks or runs passes the first
  // test on the body's speed alone (SNU's walks and runs: 38 "punches" in 30 s, 9 after
  // this test) and fails this one; a punch thrown with a step passes both (CMU's boxing
  // keeps all 52 punches, SNU's sparring 96 % of its runs). Tried and left out: calling
  // runs where both arms are fast at once swings (drops a fifth of SNU's sparring
  // punches) and runs with no foot on the ground (drops a CMU punch).
  // A library's walks and runs go further: arms pumping in a run or a dash drive the fist
  // out from the pelvis as fast as a punch (a game studio's 10 minutes of locomotion: 231
  // runs pass). With swingTravel_mps set, a run thrown while the body travels that fast over
  // the 3 s around it is a swing unless the fist also drives away from its shoulder at
  // swingMaxReach_mps: walking and running arms swing about the shoulder, a punch extends.
  // Off by default: SNU's sparring has rushes as fast (0.9 m/s drops 14 of its 258 runs).
  struct Candidate {
    EffectiveHit hit;
    double bodyDrive = 0;
    double reach = 0;  // the fist's speed away from its shoulder
  };
  std::array<std::vector<Candidate>, 2> candidates;
  // The thresholds are for a fist tip. A skeleton without fingers gives the wrist (or a
  // point near it) instead, which moves slower as the forearm turns about the elbow: scale
  // the thresholds by how far the tip found stands from the elbow against a fist's reach,
  // kFistReachPerForearm forearms (CMU's knuckles: 1.8, SNU's: 1.3; a wrist: 1.0).
  const std::vector<Eigen::Vector3d> rest = restPositions(skeleton);
  for (int s = 0; s < 2; ++s) {
    const Eigen::Vector3d elbow = rest[static_cast<std::size_t>(roles.forearm[s])];
    const double forearm = (rest[static_cast<std::size_t>(roles.wrist[s])] - elbow).norm();
    const double tip = (rest[static_cast<std::size_t>(roles.fistTipJoint[s])] + roles.fistTipOffset[s] - elbow).norm();
    result.punchScale[s] = forearm > 0 ? std::clamp(tip / (kFistReachPerForearm * forearm), 0.25, 1.0) : 1.0;
  }
  for (std::size_t f = 0; f < frames; ++f) {
    const bool down = headAbove[f] < knockdownBelow;
    result.knockdownFrames += down ? 1 : 0;
    // The pelvis's velocity, by the same central difference as the fists'.
    const std::size_t fa = f > 0 ? f - 1 : f, fb = f + 1 < frames ? f + 1 : f;
    const Eigen::Vector3d pelvisVelocity =
        fb > fa ? Eigen::Vector3d((rootPosition[fb] - rootPosition[fa]) / (static_cast<double>(fb - fa) * t.frameTime))
                : Eigen::Vector3d::Zero();
    for (int s = 0; s < 2; ++s) {
      const std::size_t base = f * kPoints;
      Eigen::Vector3d axis = points[base + 6 + s] - points[base + 8 + s];
      const Eigen::Vector3d& v = velocity[base + 4 + s];
      const double speed = v.norm();
      // A one-frame capture glitch is halved by the central difference; the one-sided
      // speeds on either side show it whole.
      const double before = f > 0 ? (points[base + 4 + s] - points[base - kPoints + 4 + s]).norm() / t.frameTime : 0;
      const double after =
          f + 1 < frames ? (points[base + kPoints + 4 + s] - points[base + 4 + s]).norm() / t.frameTime : 0;
      if (std::max({speed, before, after}) > params.punchMaxSpeed_mps) {
        ++result.glitchFrames;
      } else if (!down && axis.norm() > 1e-9) {
        axis.normalize();
        const double along = v.dot(axis);
        if (along >= params.punchMinSpeed_mps * result.punchScale[s] && along >= params.punchMinAlignment * speed) {
          Candidate c;
          c.hit.frame = static_cast<std::uint32_t>(f);
          c.hit.hand = static_cast<Side>(s);
          c.hit.tipWorld = points[base + 4 + s];
          c.hit.tipAvatar = result.frames[f].toAvatar(c.hit.tipWorld);
          c.hit.speed_mps = speed;
          c.hit.alongForearm_mps = along;
          c.bodyDrive = (v - pelvisVelocity).dot(axis);
          const Eigen::Vector3d out = points[base + 4 + s] - points[base + 15 + s];
          if (out.norm() > 1e-9) c.reach = (v - velocity[base + 15 + s]).dot(out.normalized());
          candidates[s].push_back(c);
        }
      }
    }
  }
  for (int s = 0; s < 2; ++s) {
    const std::vector<Candidate>& list = candidates[s];
    for (std::size_t i = 0; i < list.size();) {
      std::size_t end = i + 1;
      while (end < list.size() && list[end].hit.frame == list[end - 1].hit.frame + 1) ++end;
      double drive = -1e300, reach = -1e300;
      for (std::size_t k = i; k < end; ++k) {
        drive = std::max(drive, list[k].bodyDrive);
        reach = std::max(reach, list[k].reach);
      }
      const bool walking = params.swingTravel_mps > 0 && travelAround(t, list[i].hit.frame) >= params.swingTravel_mps &&
                           reach < params.swingMaxReach_mps * result.punchScale[s];
      if (!walking && drive >= params.punchMinBodySpeed_mps * result.punchScale[s]) {
        ++result.punches[s];
        for (std::size_t k = i; k < end; ++k) result.hits.push_back(list[k].hit);
      } else {
        ++result.swings[s];
      }
      i = end;
    }
  }
  // Frame order, the left hand first within a frame, as the graph expects.
  std::stable_sort(result.hits.begin(), result.hits.end(), [](const EffectiveHit& x, const EffectiveHit& y) {
    return x.frame != y.frame ? x.frame < y.frame : static_cast<int>(x.hand) < static_cast<int>(y.hand);
  });
}

void findKicks(const Tracked& t, const AnnotationParams& params, const std::vector<double>& headAbove,
               Annotation& result) {
  const std::size_t frames = t.frames;
  constexpr std::size_t kPoints = Tracked::kPoints;
  const std::vector<Eigen::Vector3d>& points = t.points;
  const std::vector<Eigen::Vector3d>& velocity = t.velocity;
  const double knockdownBelow = params.knockdownHeadRatio * result.standingHeight;
  // Effective kicks, by analogy with the punches: a fast toe tip, high enough off the floor
  // not to be a step, by a fighter on his feet, moving along the shin (knee to ankle) by at
  // least kick_min_alignment of its speed. Unlike a punch's fist, a kicking foot swings
  // (a roundhouse moves it across the shin), so the speed threshold is on the toe's whole
  // speed and the alignment can be relaxed to 0.
  std::array<bool, 2> kicking{false, false};
  for (std::size_t f = 0; f < frames; ++f) {
    const bool down = headAbove[f] < knockdownBelow;
    for (int s = 0; s < 2; ++s) {
      const std::size_t base = f * kPoints;
      const Eigen::Vector3d& tip = points[base + 10 + s];
      Eigen::Vector3d axis = points[base + s] - points[base + 13 + s];
      const Eigen::Vector3d& v = velocity[base + 10 + s];
      const double speed = v.norm();
      const double before = f > 0 ? (tip - points[base - kPoints + 10 + s]).norm() / t.frameTime : 0;
      const double after = f + 1 < frames ? (points[base + kPoints + 10 + s] - tip).norm() / t.frameTime : 0;
      bool effective = false;
      if (!down && axis.norm() > 1e-9 && std::max({speed, before, after}) <= params.kickMaxSpeed_mps &&
          tip.y() - result.groundY >= params.kickMinHeight_m) {
        axis.normalize();
        const double along = v.dot(axis);
        if (speed >= params.kickMinSpeed_mps && along >= params.kickMinAlignment * speed) {
          effective = true;
          EffectiveHit kick;
          kick.frame = static_cast<std::uint32_t>(f);
          kick.hand = static_cast<Side>(s);
          kick.tipWorld = tip;
          kick.tipAvatar = result.frames[f].toAvatar(tip);
          kick.speed_mps = speed;
          kick.alongForearm_mps = along;
          result.kicks.push_back(kick);
        }
      }
      if (effective && !kicking[s]) ++result.kickCount[s];
      kicking[s] = effective;
    }
  }
}

}  // namespace

Annotation annotate(const Motion& motion, const SkeletonRoles& roles, const AnnotationParams& params) {
  if (params.punchMinSpeedAuto) {
    const Motion* const one[] = {&motion};
    AnnotationParams chosen = params;
    chosen.punchMinSpeed_mps = autoPunchMinSpeed(one, roles, params).speed_mps;
    chosen.punchMinSpeedAuto = false;
    return annotate(motion, roles, chosen);
  }
  params.validate();
  const Tracked t = trackPoints(motion, roles);
  const std::size_t frames = t.frames;
  Annotation result;
  const std::vector<double> lowest = findContacts(t, params, result);
  const std::vector<double> headAbove = measureStanding(t, lowest, result);
  result.frames.resize(frames);
  for (std::size_t f = 0; f < frames; ++f) {
    result.frames[f].origin = {t.rootPosition[f].x(), result.groundY, t.rootPosition[f].z()};
    result.frames[f].yaw = std::atan2(t.facing[f].x(), t.facing[f].z());
  }

  findPunches(t, motion.skeleton(), roles, params, headAbove, result);
  findKicks(t, params, headAbove, result);
  return result;
}

std::vector<double> windowQuantiles(std::span<const double> values, std::size_t window, double q) {
  const std::size_t n = values.size();
  std::vector<double> result(n), sorted;
  sorted.reserve(std::min(n, 2 * window + 1));
  std::size_t lo = 0, hi = 0;  // values[lo, hi) are in `sorted`
  for (std::size_t f = 0; f < n; ++f) {
    const std::size_t first = f > window ? f - window : 0, end = std::min(n, f + window + 1);
    for (; hi < end; ++hi) sorted.insert(std::upper_bound(sorted.begin(), sorted.end(), values[hi]), values[hi]);
    for (; lo < first; ++lo) sorted.erase(std::lower_bound(sorted.begin(), sorted.end(), values[lo]));
    result[f] = sorted[quantileIndex(sorted.size(), q)];
  }
  return result;
}

std::string unusualHeightWarning(const Annotation& annotation, std::string_view source) {
  const double h = annotation.standingHeight;
  if (h >= kUsualHeightMin_m && h <= kUsualHeightMax_m) return {};
  return fmt::format("{}: standing height {:.2f} m (head top above the lower foot over {} standing frames), expected "
                     "{} to {} m for an adult; check the units (--units), the head role (--role head=JOINT) and "
                     "that the capture has frames standing upright",
                     source, h, annotation.standingFrames, kUsualHeightMin_m, kUsualHeightMax_m);
}

}  // namespace mgrl
