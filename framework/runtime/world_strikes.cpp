// The world's strikes (paper sec. 6.6): at effective-punch and kick frames, the fist or toe
// tip against the target or the partner's guard and body (World::collide), and what a hit or
// a block does to both fighters (World::react). Stepping and poses are in world.cpp.
#include <algorithm>
#include <cmath>
#include <optional>
#include <span>

#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/runtime/world_parts.hpp"

namespace mgrl {

using namespace world_detail;  // NOLINT: the world's own helpers (world_parts.hpp)

namespace {

// A body part's capsule between two BodyTable points.
struct PartCapsule {
  BodyPart part;
  int from, to;
  double radius;
};

// The part whose capsule a sphere (tip, radius) enters deepest, if it enters any.
// `point(which)` is a BodyTable point of the partner in the world.
template <class Point>
std::optional<BodyPart> deepestContact(const Eigen::Vector3d& tip, double radius, std::span<const PartCapsule> parts,
                                       const Point& point) {
  std::optional<BodyPart> met;
  double most = 0;
  for (const PartCapsule& c : parts) {
    const double depth = c.radius + radius - segmentsDistance(tip, tip, point(c.from), point(c.to));
    if (depth >= 0 && (!met || depth > most)) {
      met = c.part;
      most = depth;
    }
  }
  return met;
}

}  // namespace

void World::collide(std::size_t begin, std::size_t end, std::vector<HitEvent>& out) {
  const WorldParams& p = setup_.params;
  const double time = static_cast<double>(frame_) * model_.frameTime;
  for (std::size_t i = begin; i < end; ++i) {
    Avatar& a = avatars_[i];
    // Effective punches and kicks of the action at this frame (paper sec. 6.6: collisions
    // are checked only there).
    for (const bool kick : {false, true}) {
      if (kick && model_.actionKickBegin.empty()) continue;
      const std::vector<ActionHit>& list = kick ? model_.kicks : model_.hits;
      std::uint32_t& cursor = kick ? a.kickCursor : a.hitCursor;
      const std::uint32_t stop = kick ? model_.actionKickBegin[a.action + 1] : model_.actionHitBegin[a.action + 1];
      const double radius = kick ? p.footRadius : p.fistRadius;
      while (cursor < stop && list[cursor].offset < a.step) ++cursor;
      for (std::uint32_t h = cursor; h < stop && list[h].offset == a.step; ++h) {
        const ActionHit& hit = list[h];
        std::size_t& landed = a.landedFrame[hit.hand + (kick ? 2 : 0)];
        if (landed != kNever && landed + 1 == frame_) {  // the same strike, already landed
          landed = frame_;
          continue;
        }
        // The fist or toe tip in the world (strikes are stored in the decision's avatar frame).
        const Eigen::Vector3d tip = transformPoint(a.decision, {hit.x, hit.y, hit.z});
        HitEvent event;
        bool struck = false;
        if (a.partner < 0) {
          struck = (tip - targets_[i].centre()).norm() <= p.targetRadius + radius;
        } else {
          // The partner's forearms first: a strike that meets one is blocked there, even if
          // it also reaches the body (the glove stands in front of what it guards).
          const auto j = static_cast<std::size_t>(a.partner);
          auto point = [&](int which) { return bodyPoint(j, which); };
          const PartCapsule guards[] = {
              {BodyPart::LeftArm, BodyTable::LeftElbow, BodyTable::LeftFist, p.guardRadius},
              {BodyPart::RightArm, BodyTable::RightElbow, BodyTable::RightFist, p.guardRadius}};
          const PartCapsule body[] = {{BodyPart::Head, BodyTable::Head, BodyTable::HeadTop, p.headRadius},
                                      {BodyPart::Chest, BodyTable::Chest, BodyTable::Neck, p.chestRadius},
                                      {BodyPart::Spine, BodyTable::Pelvis, BodyTable::Chest, p.spineRadius}};
          std::optional<BodyPart> met;
          if (p.guardRadius > 0) met = deepestContact(tip, radius, guards, point);
          event.blocked = met.has_value();
          if (!met) met = deepestContact(tip, radius, body, point);
          struck = met.has_value();
          if (met) event.part = *met;
        }
        if (!struck) continue;
        landed = frame_;
        event.time = time;
        event.attacker = static_cast<std::uint32_t>(i);
        event.target = a.partner;
        event.hand = hit.hand;
        event.kick = kick;
        event.speed = hit.weight * (kick ? model_.maxKickSpeed_mps : model_.maxHitSpeed_mps);
        event.point = tip;
        out.push_back(event);
      }
    }
  }
}

void World::react(const HitEvent& event) {
  const WorldParams& p = setup_.params;
  const Avatar& attacker = avatars_[event.attacker];
  // The punch's direction: from the attacker towards the fist, on the ground plane.
  Eigen::Vector3d direction(event.point.x() - attacker.now.dx, 0, event.point.z() - attacker.now.dz);
  if (direction.norm() < 1e-6) direction = {std::sin(attacker.now.dyaw), 0, std::cos(attacker.now.dyaw)};
  direction.normalize();
  if (event.target < 0) {
    Target& t = targets_[event.attacker];
    // An impulse whose undamped swing is bend_per_speed * speed (at most bend_max).
    const double amplitude = std::min(p.bendPerSpeed * event.speed, p.bendMax);
    t.bendVelocity += 2 * M_PI * p.bendFrequency * amplitude * direction;
  } else {
    Avatar& victim = avatars_[static_cast<std::size_t>(event.target)];
    victim.part = event.part;
    victim.push = std::min(p.reactionPerSpeed * event.speed, p.reactionMax) * direction;
    victim.reactionStart = event.time;
    if (event.blocked && !event.kick) {
      // The blocked fist rebounds off the guard as much as the guard gives way.
      Avatar& striker = avatars_[event.attacker];
      striker.part = event.hand == 0 ? BodyPart::LeftArm : BodyPart::RightArm;
      striker.push = -victim.push;
      striker.reactionStart = event.time;
    }
  }
}

}  // namespace mgrl
