#include "mgrl/runtime/bout_stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <regex>

#include <fmt/format.h>

#include "mgrl/learning/real_bouts.hpp"  // facingDegrees
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/runtime/world.hpp"

namespace mgrl {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The body's points per frame in the runtime world's order (BodyTable), so the stats judge
// bodies and guards as the world does.
constexpr int kBodyPoints = BodyTable::kPoints;

struct Capsule {
  int from, to;
  double radius;
};

std::array<Capsule, 3> capsules(const StatsParams& p) {
  return {{{BodyTable::Pelvis, BodyTable::Chest, p.spineRadius_m},
           {BodyTable::Chest, BodyTable::Neck, p.chestRadius_m},
           {BodyTable::Head, BodyTable::HeadTop, p.headRadius_m}}};
}

// Chest and neck on the chain from the head down to the pelvis, as the runtime's body
// table finds them: the neck is the head's parent, the chest halfway down to the pelvis.
std::pair<int, int> chestAndNeck(const Skeleton& skeleton, const SkeletonRoles& roles, const std::string& source) {
  std::vector<int> chain;
  for (int j = roles.head; j >= 0; j = skeleton.joint(static_cast<std::size_t>(j)).parent) {
    chain.push_back(j);
    if (j == roles.pelvis) break;
  }
  if (chain.size() < 2 || chain.back() != roles.pelvis)
    throw Error(
        fmt::format("{}: expected the head joint '{}' below the pelvis joint '{}' in the hierarchy, found it "
                    "elsewhere",
                    source, skeleton.joint(static_cast<std::size_t>(roles.head)).name,
                    skeleton.joint(static_cast<std::size_t>(roles.pelvis)).name));
  const int neck = chain.size() > 2 ? chain[1] : chain[0];
  const int chest = chain.size() > 3 ? chain[chain.size() / 2] : neck;
  return {chest, neck};
}

// Ground-plane speed of joint `j` at frame `f`: central differences inside, one-sided at the ends.
double groundSpeed(const Fighter& fighter, std::size_t f, std::size_t j) {
  if (fighter.frames < 2) return 0;
  const std::size_t a = f == 0 ? 0 : f - 1, b = std::min(f + 1, fighter.frames - 1);
  const Eigen::Vector3d d = fighter.joint(b, j) - fighter.joint(a, j);
  return std::hypot(d.x(), d.z()) / (static_cast<double>(b - a) * fighter.frameTime);
}

// Who fighter `i` faces at frame `f`: the partner, or the nearest other fighter; -1 for none.
int opponent(const Bout& bout, std::size_t i, std::size_t f) {
  const std::size_t n = bout.fighters.size();
  if (bout.pairing == Pairing::Partners) return (i ^ 1U) < n ? static_cast<int>(i ^ 1U) : -1;
  int best = -1;
  double bestDistance = std::numeric_limits<double>::infinity();
  const Eigen::Vector2d here = bout.fighters[i].ground(f);
  for (std::size_t j = 0; j < n; ++j) {
    if (j == i) continue;
    const double d = (bout.fighters[j].ground(f) - here).norm();
    if (d < bestDistance) {
      bestDistance = d;
      best = static_cast<int>(j);
    }
  }
  return best;
}

// Distance from `tip` to the surface of the nearest of `target`'s capsules at frame `f`
// (negative inside).
double capsuleGap(const Fighter& target, std::size_t f, const Eigen::Vector3d& tip, const StatsParams& params) {
  double gap = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d* body = target.body.data() + f * kBodyPoints;
  for (const Capsule& c : capsules(params))
    gap = std::min(gap, segmentsDistance(tip, tip, body[c.from], body[c.to]) - c.radius);
  return gap;
}

// Distance from `tip` to the nearer of `target`'s forearms (elbow to fist tip) at frame `f`.
double guardGap(const Fighter& target, std::size_t f, const Eigen::Vector3d& tip) {
  const Eigen::Vector3d* body = target.body.data() + f * kBodyPoints;
  return std::min(segmentsDistance(tip, tip, body[BodyTable::LeftElbow], body[BodyTable::LeftFist]),
                  segmentsDistance(tip, tip, body[BodyTable::RightElbow], body[BodyTable::RightFist]));
}

bool capsulesOverlap(const Fighter& a, const Fighter& b, std::size_t f, const StatsParams& params) {
  const Eigen::Vector3d* pa = a.body.data() + f * kBodyPoints;
  const Eigen::Vector3d* pb = b.body.data() + f * kBodyPoints;
  for (const Capsule& ca : capsules(params))
    for (const Capsule& cb : capsules(params))
      if (segmentsDistance(pa[ca.from], pa[ca.to], pb[cb.from], pb[cb.to]) < ca.radius + cb.radius) return true;
  return false;
}

// Whether one of a's forearms (elbow to fist tip) runs inside one of b's body capsules at
// frame f: the forearm's axis closer to the capsule's axis than the capsule's radius (a
// limb through the other fighter's torso or head).
bool forearmInside(const Fighter& a, const Fighter& b, std::size_t f, const StatsParams& params) {
  const Eigen::Vector3d* pa = a.body.data() + f * kBodyPoints;
  const Eigen::Vector3d* pb = b.body.data() + f * kBodyPoints;
  for (const auto& [elbow, fist] :
       {std::pair{BodyTable::LeftElbow, BodyTable::LeftFist}, std::pair{BodyTable::RightElbow, BodyTable::RightFist}})
    for (const Capsule& c : capsules(params))
      if (segmentsDistance(pa[elbow], pa[fist], pb[c.from], pb[c.to]) < c.radius) return true;
  return false;
}

// Strikes of one kind (punches or kicks) of fighter `i`: runs of consecutive effective
// frames per limb, as the annotation counts them. Frame by frame, a run is blocked when its
// tip first comes within the block radius of an opponent's forearm (elbow to fist tip), and
// lands when it first comes within the land radius of an opponent's capsules (a frame that
// does both is a block: the glove stands in front of what it guards); else it missed.
void countStrikes(const Bout& bout, std::size_t i, const std::vector<EffectiveHit>& hits, const StatsParams& params,
                  std::size_t& strikes, std::size_t& landed, std::size_t& blocked) {
  enum class Outcome { Open, Landed, Blocked };
  for (const Side side : {Side::Left, Side::Right}) {
    bool inRun = false;
    Outcome outcome = Outcome::Open;
    auto close = [&] {
      if (inRun && outcome == Outcome::Landed) ++landed;
      if (inRun && outcome == Outcome::Blocked) ++blocked;
    };
    std::uint32_t previous = 0;
    for (const EffectiveHit& hit : hits) {
      if (hit.hand != side) continue;
      if (!inRun || hit.frame != previous + 1) {
        close();
        inRun = true;
        outcome = Outcome::Open;
        ++strikes;
      }
      previous = hit.frame;
      if (outcome != Outcome::Open) continue;
      for (std::size_t j = 0; j < bout.fighters.size() && outcome != Outcome::Blocked; ++j) {
        if (j == i) continue;
        if (bout.pairing == Pairing::Partners && static_cast<int>(j) != opponent(bout, i, hit.frame)) continue;
        if (params.blockRadius_m > 0 && guardGap(bout.fighters[j], hit.frame, hit.tipWorld) <= params.blockRadius_m)
          outcome = Outcome::Blocked;
        else if (capsuleGap(bout.fighters[j], hit.frame, hit.tipWorld, params) <= params.landRadius_m)
          outcome = Outcome::Landed;
      }
    }
    close();
  }
}

}  // namespace

void StatsParams::validate() const {
  auto positive = [](double value, const char* name) {
    if (!(value > 0) || !std::isfinite(value))
      throw Error(fmt::format("{}: expected a positive number, found {}", name, value));
  };
  if (!(landRadius_m >= 0) || !std::isfinite(landRadius_m))
    throw Error(fmt::format("--land-radius: expected a distance >= 0 (m), found {}", landRadius_m));
  if (!(blockRadius_m >= 0) || !std::isfinite(blockRadius_m))
    throw Error(fmt::format("--block-radius: expected a distance >= 0 (m), found {}", blockRadius_m));
  positive(closeDistance_m, "--close-distance");
  if (!(reversalMinSpeed_mps >= 0) || !std::isfinite(reversalMinSpeed_mps))
    throw Error(fmt::format("--reversal-min-speed: expected a speed >= 0 (m/s), found {}", reversalMinSpeed_mps));
  positive(spineRadius_m, "spine radius");
  positive(chestRadius_m, "chest radius");
  positive(headRadius_m, "head radius");
  annotation.validate();
}

const char* pairingName(Pairing pairing) { return pairing == Pairing::Partners ? "partners" : "nearest"; }

Eigen::Vector2d Fighter::ground(std::size_t frame) const {
  const Eigen::Vector3d& p = body[frame * kBodyPoints + BodyTable::Pelvis];
  return {p.x(), p.z()};
}

Fighter makeFighter(const Motion& motion, std::string source, const StatsParams& params) {
  Fighter fighter;
  const Skeleton& skeleton = motion.skeleton();
  // A wrist standing in for a missing fist joint (SNU) is what the annotation does anyway;
  // its warning would only repeat for every fighter, so it is not passed on.
  fighter.roles = findRoles(skeleton, {}, source, {});
  fighter.annotation = annotate(motion, fighter.roles, params.annotation);
  fighter.source = std::move(source);
  fighter.frames = motion.frameCount();
  fighter.frameTime = motion.frameTime();
  fighter.joints = skeleton.jointCount();
  const auto [chest, neck] = chestAndNeck(skeleton, fighter.roles, fighter.source);
  const auto head = static_cast<std::size_t>(fighter.roles.head);
  const auto pelvis = static_cast<std::size_t>(fighter.roles.pelvis);

  fighter.positions.resize(fighter.frames * fighter.joints);
  fighter.body.resize(fighter.frames * kBodyPoints);
  fighter.facing.resize(fighter.frames);
  std::vector<Eigen::Quaterniond> rotations(fighter.joints);
  for (std::size_t f = 0; f < fighter.frames; ++f) {
    const std::span<Eigen::Vector3d> positions(fighter.positions.data() + f * fighter.joints, fighter.joints);
    forwardKinematics(motion, f, rotations, positions);
    Eigen::Vector3d* body = fighter.body.data() + f * kBodyPoints;
    body[BodyTable::Pelvis] = positions[pelvis];
    body[BodyTable::Chest] = positions[static_cast<std::size_t>(chest)];
    body[BodyTable::Neck] = positions[static_cast<std::size_t>(neck)];
    body[BodyTable::Head] = positions[head];
    body[BodyTable::HeadTop] = pointOnJoint(rotations, positions, head, fighter.roles.headTopOffset);
    for (int side = 0; side < 2; ++side) {
      body[side == 0 ? BodyTable::LeftElbow : BodyTable::RightElbow] =
          positions[static_cast<std::size_t>(fighter.roles.forearm[side])];
      body[side == 0 ? BodyTable::LeftFist : BodyTable::RightFist] =
          pointOnJoint(rotations, positions, static_cast<std::size_t>(fighter.roles.fistTipJoint[side]),
                       fighter.roles.fistTipOffset[side]);
    }
    const double yaw = fighter.annotation.frames[f].yaw;  // atan2(x, z) of the facing axis
    fighter.facing[f] = {std::sin(yaw), std::cos(yaw)};
  }
  return fighter;
}

Bout loadBout(const std::string& name, const std::vector<std::filesystem::path>& files, const StatsParams& params,
              const WarningSink& warn) {
  if (files.size() < 2)
    throw Error(fmt::format("bout {}: expected at least 2 fighters (BVH files), found {}{}", name, files.size(),
                            files.empty() ? std::string() : fmt::format(" ({})", files.front().string())));
  std::vector<LoadedMotion> loaded;
  for (const auto& file : files) {
    LoadOptions options;
    options.warn = warn;
    loaded.push_back(loadMotion(file, options));
  }
  std::size_t shortest = 0;
  for (std::size_t i = 0; i < loaded.size(); ++i) {
    const double t0 = loaded[0].motion.frameTime(), t = loaded[i].motion.frameTime();
    if (std::abs(t - t0) > 1e-6 * t0)
      throw Error(
          fmt::format("bout {}: expected one frame time for all fighters, found {:.6g} s in {} and {:.6g} s "
                      "in {}",
                      name, t0, files[0].string(), t, files[i].string()));
    if (loaded[i].motion.frameCount() < loaded[shortest].motion.frameCount()) shortest = i;
  }
  const std::size_t frames = loaded[shortest].motion.frameCount();
  if (frames < 2)
    throw Error(fmt::format("{}: expected at least 2 frames, found {}", files[shortest].string(), frames));
  Bout bout;
  bout.name = name;
  static const std::regex avatarName(R"(avatar_\d+\.bvh)");
  bout.pairing = std::all_of(files.begin(), files.end(),
                             [](const auto& f) { return std::regex_match(f.filename().string(), avatarName); })
                     ? Pairing::Partners
                     : Pairing::Nearest;
  for (std::size_t i = 0; i < loaded.size(); ++i) {
    const Motion& motion = loaded[i].motion;
    if (motion.frameCount() != frames && warn)
      warn(fmt::format("bout {}: {} has {} frames, {} only {}: measuring the first {} frames of each", name,
                       files[i].string(), motion.frameCount(), files[shortest].string(), frames, frames));
    bout.fighters.push_back(
        makeFighter(motion.frameCount() == frames ? motion : motion.slice(0, frames), files[i].string(), params));
  }
  return bout;
}

BoutStats measureBout(const Bout& bout, const StatsParams& params) {
  BoutStats s;
  s.name = bout.name;
  s.bouts = 1;
  s.fighters = bout.fighters.size();
  const Fighter& first = bout.fighters.front();
  s.frames = first.frames;
  const double dt = first.frameTime;
  s.fps.push_back(1.0 / dt);
  s.seconds = static_cast<double>(s.frames) * dt;
  s.fighterSeconds = s.seconds * static_cast<double>(s.fighters);

  for (std::size_t i = 0; i < bout.fighters.size(); ++i) {
    const Fighter& me = bout.fighters[i];
    // 1, 2, 7: distance, facing and interpenetration, against the opponent of each frame.
    for (std::size_t f = 0; f < me.frames; ++f) {
      const int j = opponent(bout, i, f);
      if (j < 0) continue;
      const Fighter& other = bout.fighters[static_cast<std::size_t>(j)];
      const Eigen::Vector2d toOther = other.ground(f) - me.ground(f);
      const double distance = toOther.norm();
      ++s.pairFrames;
      s.distance_m.push_back(distance);
      if (distance > 1e-9) s.facing_deg.push_back(facingDegrees(me.facing[f], toOther, distance));
      if (distance < params.closeDistance_m) ++s.closeFrames;
      if (capsulesOverlap(me, other, f, params)) ++s.overlapFrames;
      if (forearmInside(me, other, f, params)) ++s.forearmInsideFrames;
    }
    // 3: strikes and landed strikes, for the bout and for this fighter.
    const std::size_t punches = s.punches, kicks = s.kicks, landed = s.landed, blocked = s.blocked;
    countStrikes(bout, i, me.annotation.hits, params, s.punches, s.landed, s.blocked);
    countStrikes(bout, i, me.annotation.kicks, params, s.kicks, s.landed, s.blocked);
    s.sides.push_back(
        {me.source, s.punches - punches + s.kicks - kicks, s.landed - landed, s.blocked - blocked, s.seconds});
    // 4: planted feet.
    for (int side = 0; side < 2; ++side) {
      const auto ankle = static_cast<std::size_t>(me.roles.ankle[side]);
      const auto toe = static_cast<std::size_t>(me.roles.toe[side]);
      for (std::size_t f = 0; f < me.frames; ++f) {
        if (!me.annotation.contact[side][f]) continue;
        const double ankleSpeed = groundSpeed(me, f, ankle), toeSpeed = groundSpeed(me, f, toe);
        s.plantedFootSpeed_mps.push_back(std::min(ankleSpeed, toeSpeed));
        s.plantedAnkleSpeed_mps.push_back(ankleSpeed);
        s.plantedToeSpeed_mps.push_back(toeSpeed);
      }
    }
    // 5: reversals. The direction of travel is that of the last step faster than the
    // threshold; a reversal is a step faster than the threshold whose velocity points
    // against it (a negative dot product). Slower steps neither count nor reset it.
    Eigen::Vector2d direction = Eigen::Vector2d::Zero();
    bool moving = false;
    for (std::size_t f = 0; f + 1 < me.frames; ++f) {
      const Eigen::Vector2d velocity = (me.ground(f + 1) - me.ground(f)) / dt;
      ++s.rootSteps;
      s.stepSeconds += dt;
      const double speed = velocity.norm();
      if (speed < params.reversalMinSpeed_mps || speed == 0) continue;
      if (moving && velocity.dot(direction) < 0) ++s.reversals;
      direction = velocity / speed;
      moving = true;
    }
    // 6: joint steps.
    for (std::size_t f = 0; f + 1 < me.frames; ++f)
      for (std::size_t j = 0; j < me.joints; ++j) {
        const double step = (me.joint(f + 1, j) - me.joint(f, j)).norm();
        s.jointStep_m.push_back(step);
        s.jointSpeed_mps.push_back(step / dt);
      }
  }
  // 3, each way: the pairs are simulate's partners, or the two fighters of a two-fighter
  // bout (with more, nearest-opponent pairing has no fixed pairs).
  const std::size_t pairs = bout.pairing == Pairing::Partners ? s.sides.size() / 2 : s.sides.size() == 2 ? 1 : 0;
  for (std::size_t k = 0; k < pairs; ++k) {
    const std::size_t a = s.sides[2 * k].landed, b = s.sides[2 * k + 1].landed;
    s.landedByMore += std::max(a, b);
    s.landedInPairs += a + b;
  }
  return s;
}

BoutStats pool(const std::vector<BoutStats>& bouts, const std::string& name) {
  // Every count and sum adds up over bouts, every per-frame sample list concatenates: a
  // new field of BoutStats goes into one of these lists.
  static constexpr std::size_t BoutStats::*kCounts[] = {
      &BoutStats::bouts,        &BoutStats::fighters,      &BoutStats::frames,
      &BoutStats::rootSteps,    &BoutStats::reversals,     &BoutStats::punches,
      &BoutStats::kicks,        &BoutStats::landed,        &BoutStats::blocked,
      &BoutStats::landedByMore, &BoutStats::landedInPairs, &BoutStats::pairFrames,
      &BoutStats::closeFrames,  &BoutStats::overlapFrames, &BoutStats::forearmInsideFrames};
  static constexpr double BoutStats::*kSums[] = {&BoutStats::seconds, &BoutStats::fighterSeconds,
                                                 &BoutStats::stepSeconds};
  static constexpr std::vector<double> BoutStats::*kSamples[] = {&BoutStats::fps,
                                                                 &BoutStats::distance_m,
                                                                 &BoutStats::facing_deg,
                                                                 &BoutStats::plantedFootSpeed_mps,
                                                                 &BoutStats::plantedAnkleSpeed_mps,
                                                                 &BoutStats::plantedToeSpeed_mps,
                                                                 &BoutStats::jointStep_m,
                                                                 &BoutStats::jointSpeed_mps};
  static_assert(sizeof(BoutStats) == sizeof(std::string) + std::size(kCounts) * sizeof(std::size_t) +
                                         std::size(kSums) * sizeof(double) +
                                         (std::size(kSamples) + 1) * sizeof(std::vector<double>),
                "a field of BoutStats is missing from pool's lists");
  BoutStats p;
  p.name = name;
  for (const BoutStats& b : bouts) {
    for (const auto count : kCounts) p.*count += b.*count;
    for (const auto sum : kSums) p.*sum += b.*sum;
    for (const auto samples : kSamples)
      (p.*samples).insert((p.*samples).end(), (b.*samples).begin(), (b.*samples).end());
    p.sides.insert(p.sides.end(), b.sides.begin(), b.sides.end());
  }
  return p;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  const double at = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(lo), values.end());
  const double low = values[lo];
  if (hi == lo) return low;
  const double high = *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(lo) + 1, values.end());
  return low + (at - static_cast<double>(lo)) * (high - low);
}

double wasserstein1(std::vector<double> a, std::vector<double> b) {
  if (a.empty() || b.empty()) return kNaN;
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  // Walk the merged order statistics; between consecutive values x and x', the two
  // empirical CDFs are constant, so |F_a - F_b| (x' - x) adds up the integral exactly.
  const double na = static_cast<double>(a.size()), nb = static_cast<double>(b.size());
  std::size_t i = 0, k = 0;
  double total = 0, x = std::min(a[0], b[0]);
  while (i < a.size() || k < b.size()) {
    const double next = k == b.size() || (i < a.size() && a[i] <= b[k]) ? a[i] : b[k];
    total += std::abs(static_cast<double>(i) / na - static_cast<double>(k) / nb) * (next - x);
    x = next;
    while (i < a.size() && a[i] == x) ++i;
    while (k < b.size() && b[k] == x) ++k;
  }
  return total;
}

}  // namespace mgrl
