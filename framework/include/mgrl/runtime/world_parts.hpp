#pragma once
// The world's internals shared by the files that implement it (world.hpp): world.cpp
// (stepping, poses), world_strikes.cpp (strikes, blocks, reactions) and world_bodies.cpp
// (body collisions). Not for
// other code: include mgrl/runtime/world.hpp.
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "mgrl/graph/playback.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/runtime/world.hpp"

namespace mgrl::world_detail {

inline constexpr std::size_t kNever = std::numeric_limits<std::size_t>::max();

// How far apart two torsos are: the distance between their capsules' axes, and never
// more than their pelvises' distance on the floor (a torso leaning away must not let the
// hips meet).
inline double torsoDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& h0, const Eigen::Vector3d& p1,
                            const Eigen::Vector3d& h1) {
  return std::min(segmentsDistance(p0, h0, p1, h1), std::hypot(p0.x() - p1.x(), p0.z() - p1.z()));
}

// A grid cell (x, z) packed in one integer, and its bucket in a hashed table.
inline std::int64_t packCell(std::int64_t x, std::int64_t z) { return (x << 32) ^ (z & 0xffffffff); }
inline std::size_t cellBucket(std::int64_t cell, std::size_t mask) {
  auto h = static_cast<std::uint64_t>(cell) * 0x9e3779b97f4a7c15ULL;
  return static_cast<std::size_t>(h >> 32) & mask;
}

}  // namespace mgrl::world_detail

namespace mgrl {

struct World::Avatar {
  Rng rng;
  GroundMotion decision;  ///< avatar frame at the last decision (world)
  GroundMotion now;       ///< avatar frame at the frame shown (world)
  std::uint32_t state = 0, action = 0, step = 0, length = 0;
  std::uint32_t sourceFrame = 0;
  std::uint32_t hitCursor = 0;   ///< next hit of the action to check
  std::uint32_t kickCursor = 0;  ///< next kick of the action to check
  std::int32_t partner = -1;
  std::int32_t stance = -1;  ///< the stance held (WorldSetup::stances), until stanceUntil (s)
  double stanceUntil = 0;
  /// Last frame of a landed strike, per limb: left and right fist, left and right foot.
  std::array<std::size_t, 4> landedFrame{world_detail::kNever, world_detail::kNever, world_detail::kNever,
                                         world_detail::kNever};
  std::size_t decisions = 0;
  TargetState decisionTarget;  ///< e at the last decision, as the controller saw it
  // Reaction to the last hit taken: displacement `push` of `part`, starting at `reactionStart`.
  BodyPart part = BodyPart::Head;
  Eigen::Vector3d push = Eigen::Vector3d::Zero();
  double reactionStart = -1e30;
  // Poses (only when asked for).
  std::unique_ptr<ActionPlayback> playback;
  Pose pose;
  std::vector<Pose> recorded;
};

// What the other avatars may read of avatar i while it moves: where the last frame left it.
struct World::Track {
  GroundMotion decision;
  double c = 1, s = 0;  ///< cosine and sine of decision.dyaw
  std::uint32_t action = 0, step = 0, length = 0;
  Segment now;
};

}  // namespace mgrl
