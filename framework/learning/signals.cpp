#include "mgrl/learning/signals.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

BodyPoint parseBodyPoint(std::string_view name) {
  if (name == "centroid") return BodyPoint::Centroid;
  if (name == "pelvis") return BodyPoint::Pelvis;
  throw Error(fmt::format("expected a body point (centroid, pelvis), found {}", quoteToken(name)));
}

std::string_view bodyPointName(BodyPoint point) { return point == BodyPoint::Centroid ? "centroid" : "pelvis"; }

std::uint8_t parseEffector(std::string_view name) {
  static constexpr std::uint8_t kBits[] = {kFists, kLeftFist, kRightFist, kFeet, kLeftFoot, kRightFoot, kAnyLimb};
  for (std::size_t i = 0; i < std::size(kEffectorNames); ++i)
    if (name == kEffectorNames[i]) return kBits[i];
  throw Error(fmt::format("expected an effector ({}), found {}", fmt::join(kEffectorNames, ", "), quoteToken(name)));
}

double bodyDistance(const StateActionModel& m, std::size_t frame, BodyPoint point, int dims, const Eigen::Vector3d& e) {
  if (point == BodyPoint::Pelvis) {
    const double* r = &m.frameRoot[3 * frame];
    return std::hypot(r[0] - e.x(), r[1] - e.z());
  }
  const float* p = &m.frameCentroid[3 * frame];
  if (dims == 3) return std::sqrt(std::pow(p[0] - e.x(), 2) + std::pow(p[1] - e.y(), 2) + std::pow(p[2] - e.z(), 2));
  return std::hypot(p[0] - e.x(), p[2] - e.z());
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
