#include "mgrl/learning/signals.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/graph/motion_graph.hpp"
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

double facingError(const StateActionModel& m, std::size_t frame, const Eigen::Vector3d& e) {
  const double* r = &m.frameRoot[3 * frame];
  const double dx = e.x() - r[0], dz = e.z() - r[1];
  if (dx == 0 && dz == 0) return 0;
  // Angles from +Z towards +X, as the avatar's yaw (DESIGN.md sec. 3).
  double angle = std::atan2(dx, dz) - r[2];
  angle = std::remainder(angle, 2 * std::numbers::pi);
  return std::abs(angle);
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

}  // namespace mgrl
