#include "mgrl/learning/signals.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/environment_model.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl {

BodyPoint parseBodyPoint(std::string_view name) {
  if (name == "centroid") return BodyPoint::centroid();
  if (name == "pelvis") return BodyPoint::pelvis();
  if (name == "body") return {BodyPoint::Kind::Body, "body", -1};
  if (name.empty()) throw Error("expected a body point (centroid, pelvis, a role or a joint), found an empty name");
  return {BodyPoint::Kind::Joint, std::string(name), -1};
}

std::string_view bodyPointName(const BodyPoint& point) { return point.name; }

bool bindBodyPoint(const StateActionModel& m, BodyPoint& point, std::string* why) {
  if (point.kind == BodyPoint::Kind::Body && m.jointNames.empty()) {
    if (why) *why = "no joints for body: this model records no skeleton joints";
    return false;
  }
  if (point.kind != BodyPoint::Kind::Joint) return true;
  const std::vector<std::string> roles = roleNames();
  point.joint = -1;
  for (std::size_t r = 0; r < roles.size() && r < m.roleJoint.size(); ++r)
    if (roles[r] == point.name) point.joint = m.roleJoint[r];
  for (std::size_t j = 0; point.joint < 0 && j < m.jointNames.size(); ++j)
    if (m.jointNames[j] == point.name) point.joint = static_cast<int>(j);
  if (point.joint >= 0) return true;
  if (why) {
    if (m.jointNames.empty())
      *why = fmt::format("no joint {}: this model records no skeleton joints", quoteToken(point.name));
    else {
      // "pelvis" is the ground point; its joint goes by its own name.
      std::vector<std::string> named;
      for (const std::string& r : roles)
        if (r != "pelvis") named.push_back(r);
      *why = fmt::format("expected centroid, pelvis, a role ({}) or a joint of this skeleton ({}), found {}",
                         fmt::join(named, ", "), fmt::join(m.jointNames, ", "), quoteToken(point.name));
    }
  }
  return false;
}

std::uint8_t parseEffector(std::string_view name) {
  static constexpr std::uint8_t kBits[] = {kFists, kLeftFist, kRightFist, kFeet, kLeftFoot, kRightFoot, kAnyLimb};
  for (std::size_t i = 0; i < std::size(kEffectorNames); ++i)
    if (name == kEffectorNames[i]) return kBits[i];
  throw Error(fmt::format("expected an effector ({}), found {}", fmt::join(kEffectorNames, ", "), quoteToken(name)));
}

double bodyDistance(const StateActionModel& m, std::size_t frame, const BodyPoint& point, int dims,
                    const Eigen::Vector3d& e) {
  if (point.kind == BodyPoint::Kind::Pelvis) {
    const double* r = &m.frameRoot[3 * frame];
    return std::hypot(r[0] - e.x(), r[1] - e.z());
  }
  Eigen::Vector3d p;
  if (point.kind == BodyPoint::Kind::Joint) {
    p = jointAt(m, frame, point.joint);
  } else {
    const float* c = &m.frameCentroid[3 * frame];
    p = {c[0], c[1], c[2]};
  }
  if (dims == 3) return std::sqrt(std::pow(p[0] - e.x(), 2) + std::pow(p[1] - e.y(), 2) + std::pow(p[2] - e.z(), 2));
  return std::hypot(p[0] - e.x(), p[2] - e.z());
}

Eigen::Vector3d jointAt(const StateActionModel& m, std::size_t frame, int joint) {
  // The joint in its own frame's avatar frame, carried to the decision's as frameCentroid is.
  const std::size_t joints = m.jointNames.size();
  const float* q = &m.sourceJoint[3 * (m.actionFrames[frame] * joints + static_cast<std::size_t>(joint))];
  const double* r = &m.frameRoot[3 * frame];
  return transformPoint({r[0], r[1], r[2]}, Eigen::Vector3d(q[0], q[1], q[2]));
}

double bodySpeed(const StateActionModel& m, std::size_t frame, const BodyPoint& point) {
  const std::size_t joints = m.jointNames.size();
  if (joints == 0) return 0;  // bindBodyPoint() refuses this
  const float* v = m.sourceJointSpeed.data() + m.actionFrames[frame] * joints;
  if (point.kind == BodyPoint::Kind::Joint) return v[point.joint];
  double sum = 0;
  for (std::size_t j = 0; j < joints; ++j) sum += v[j];
  return sum / static_cast<double>(joints);
}

double signedFacing(const StateActionModel& m, std::size_t frame, const Eigen::Vector3d& e) {
  const double* r = &m.frameRoot[3 * frame];
  const double dx = e.x() - r[0], dz = e.z() - r[1];
  if (dx == 0 && dz == 0) return 0;
  // Angles from +Z towards +X, as the avatar's yaw (DESIGN.md sec. 3).
  return std::remainder(std::atan2(dx, dz) - r[2], 2 * std::numbers::pi);
}

double facingError(const StateActionModel& m, std::size_t frame, const Eigen::Vector3d& e) {
  return std::abs(signedFacing(m, frame, e));
}

double rootSpeed(const StateActionModel& m, std::size_t a, std::size_t t) {
  const std::size_t frame = m.actionFrameBegin[a] + t - 1;
  const double* r = &m.frameRoot[3 * frame];
  const double px = t > 1 ? r[-3] : 0, pz = t > 1 ? r[-2] : 0;
  return std::hypot(r[0] - px, r[1] - pz) / m.frameTime;
}

double strikeAt(const StateActionModel& m, std::size_t a, std::uint32_t t, std::uint8_t effectors, double radius,
                bool useSpeed, const Eigen::Vector3d& e) {
  double best = 0;
  auto scan = [&](std::span<const ActionHit> strikes, std::uint8_t leftBit) {
    for (const ActionHit& h : strikes) {
      if (h.offset != t || !(effectors & (leftBit << h.hand))) continue;
      const double dx = h.x - e.x(), dy = h.y - e.y(), dz = h.z - e.z();
      if (dx * dx + dy * dy + dz * dz > radius * radius) continue;
      best = std::max(best, useSpeed ? static_cast<double>(h.weight) : 1.0);
    }
  };
  if (effectors & kFists) scan(m.hitsOf(a), kLeftFist);
  if (effectors & kFeet) scan(m.kicksOf(a), kLeftFoot);
  return best;
}

StrikeReach::StrikeReach(const StateActionModel& m, std::uint8_t effectors, double cap) : cap_(cap) {
  if (!(cap > 0 && cap <= 1)) throw Error(fmt::format("strike reach: expected a cap in (0, 1] m, found {}", cap));
  // Each tip seen from the striker's root at the strike's frame (ActionHit is in the
  // decision's frame; frameRoot carries that frame to the strike's), deduplicated to 1 cm:
  // actions that share capture frames share strikes.
  std::vector<std::array<std::int32_t, 3>> keys;
  auto collect = [&](const std::vector<ActionHit>& strikes, std::uint8_t leftBit) {
    for (const ActionHit& h : strikes) {
      if (!(effectors & (leftBit << h.hand))) continue;
      const double* r = &m.frameRoot[3 * (m.actionFrameBegin[h.action] + h.offset - 1)];
      const Eigen::Vector3d tip = inverseTransformPoint({r[0], r[1], r[2]}, Eigen::Vector3d(h.x, h.y, h.z));
      keys.push_back({static_cast<std::int32_t>(std::lround(tip.x() * 100)),
                      static_cast<std::int32_t>(std::lround(tip.y() * 100)),
                      static_cast<std::int32_t>(std::lround(tip.z() * 100))});
    }
  };
  if (effectors & kFists) collect(m.hits, kLeftFist);
  if (effectors & kFeet) collect(m.kicks, kLeftFoot);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  if (keys.empty()) throw Error("no effective strike of these limbs in this capture: an opponent playing it never reaches");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
  for (const auto& k : keys) {
    tips_.emplace_back(k[0] / 100.0F, k[1] / 100.0F, k[2] / 100.0F);
    lo = lo.cwiseMin(tips_.back().cast<double>());
    hi = hi.cwiseMax(tips_.back().cast<double>());
  }
  // The field covers the tips' box widened by cap: beyond it every distance is >= cap.
  origin_ = lo - Eigen::Vector3d::Constant(cap);
  for (int k = 0; k < 3; ++k) n_[k] = static_cast<int>(std::ceil((hi[k] - lo[k] + 2 * cap) / kCell)) + 1;
  field_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2], static_cast<float>(cap));
  std::size_t i = 0;
  for (int z = 0; z < n_[2]; ++z)
    for (int y = 0; y < n_[1]; ++y)
      for (int x = 0; x < n_[0]; ++x, ++i) {
        const Eigen::Vector3f p = (origin_ + kCell * Eigen::Vector3d(x, y, z)).cast<float>();
        float best = static_cast<float>(cap * cap);
        for (const Eigen::Vector3f& t : tips_) best = std::min(best, (t - p).squaredNorm());
        field_[i] = std::sqrt(best);
      }
}

double StrikeReach::distance(const Eigen::Vector3d& p) const {
  double f[3];
  int c[3];
  for (int k = 0; k < 3; ++k) {
    const double u = (p[k] - origin_[k]) / kCell;
    if (!(u >= 0 && u <= n_[k] - 1)) return cap_;  // outside the box: at least cap from every tip
    c[k] = std::min(static_cast<int>(u), n_[k] - 2);
    f[k] = u - c[k];
  }
  // Trilinear: the exact distance is 1-Lipschitz, so the error is below a cell's diagonal.
  const std::size_t sx = 1, sy = static_cast<std::size_t>(n_[0]), sz = sy * static_cast<std::size_t>(n_[1]);
  const std::size_t base = c[0] * sx + c[1] * sy + c[2] * sz;
  double result = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int bx = corner & 1, by = (corner >> 1) & 1, bz = (corner >> 2) & 1;
    const double w = (bx ? f[0] : 1 - f[0]) * (by ? f[1] : 1 - f[1]) * (bz ? f[2] : 1 - f[2]);
    result += w * field_[base + bx * sx + by * sy + bz * sz];
  }
  return std::min(result, cap_);
}

Eigen::Vector3d inOpponentFrame(const TargetState& e, const Eigen::Vector3d& p) {
  // The opponent's frame is the decision's moved to its ground point and turned by its
  // facing, as an action's end frame is by its displacement.
  return inverseTransformPoint({e.position.x(), e.position.z(), e.heading}, p);
}

double opponentClearance(const StateActionModel& m, std::size_t frame, int joint, const StrikeReach& reach,
                         const TargetState& e, double bodyRadius) {
  const double bodies = bodyDistance(m, frame, BodyPoint::pelvis(), 2, e.position) - 2 * bodyRadius;
  const double strikes = reach.distance(inOpponentFrame(e, jointAt(m, frame, joint)));
  return std::max(0.0, std::min(strikes, bodies));
}

GroundMotion actionFrameMotion(const StateActionModel& m, std::size_t a, std::uint32_t k) {
  if (k == 0) return {};
  const double* r = &m.frameRoot[3 * (m.actionFrameBegin[a] + k - 1)];
  return {r[0], r[1], r[2]};
}

Eigen::Vector3d applyMotion(const GroundMotion& g, const Eigen::Vector3d& p) { return transformPoint(g, p); }

GroundMotion composeMotion(const GroundMotion& a, const GroundMotion& b) { return compose(a, b); }

int headJoint(const StateActionModel& m) {
  BodyPoint head = parseBodyPoint("head");
  return bindBodyPoint(m, head, nullptr) ? head.joint : -1;
}

Eigen::Vector3d opponentTarget(const StateActionModel& m, const OpponentFrame& o, int head, double height) {
  if (head >= 0) return o.toAvatar(jointAt(m, o.frame(m), head));
  Eigen::Vector3d e = o.ground(m);
  e.y() = height;
  return e;
}

double trackedStrikeAt(const StateActionModel& m, std::size_t frame, int joint, const OpponentFrame& o,
                       std::uint8_t effectors, double radius, bool useSpeed) {
  const Eigen::Vector3d p = jointAt(m, frame, joint);
  double best = 0;
  auto scan = [&](std::span<const ActionHit> strikes, std::uint8_t leftBit) {
    for (const ActionHit& h : strikes) {
      if (h.offset != o.offset || !(effectors & (leftBit << h.hand))) continue;
      if ((o.toAvatar(Eigen::Vector3d(h.x, h.y, h.z)) - p).norm() > radius) continue;
      best = std::max(best, useSpeed ? static_cast<double>(h.weight) : 1.0);
    }
  };
  if (effectors & kFists) scan(m.hitsOf(o.action), kLeftFist);
  if (effectors & kFeet) scan(m.kicksOf(o.action), kLeftFoot);
  return best;
}

double trackedClearance(const StateActionModel& m, std::size_t frame, int joint, const OpponentFrame& o,
                        std::uint8_t effectors, std::uint32_t window, double cap, double bodyRadius) {
  double nearest = cap;
  const Eigen::Vector3d p = jointAt(m, frame, joint);
  nearest = std::min(nearest, bodyDistance(m, frame, BodyPoint::pelvis(), 2, o.ground(m)) - 2 * bodyRadius);
  auto scan = [&](std::span<const ActionHit> strikes, std::uint8_t leftBit) {
    for (const ActionHit& h : strikes) {
      if (!(effectors & (leftBit << h.hand))) continue;
      if (h.offset + window < o.offset || h.offset > o.offset + window) continue;
      nearest = std::min(nearest, (o.toAvatar(Eigen::Vector3d(h.x, h.y, h.z)) - p).norm());
    }
  };
  if (effectors & kFists) scan(m.hitsOf(o.action), kLeftFist);
  if (effectors & kFeet) scan(m.kicksOf(o.action), kLeftFoot);
  return std::max(0.0, nearest);
}

}  // namespace mgrl
