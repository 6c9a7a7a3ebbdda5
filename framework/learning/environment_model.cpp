#include "mgrl/learning/environment_model.hpp"

#include <cmath>

namespace mgrl {

Eigen::Vector3d inverseTransformPoint(const GroundMotion& motion, const Eigen::Vector3d& point) {
  // transformPoint maps p to (dx, dz) + R p with R = [[c, s], [-s, c]] on (x, z); invert it.
  const double c = std::cos(motion.dyaw), s = std::sin(motion.dyaw);
  const double qx = point.x() - motion.dx, qz = point.z() - motion.dz;
  return {c * qx - s * qz, point.y(), s * qx + c * qz};
}

TargetState StaticTarget::next(const StateActionModel& model, std::size_t action, const TargetState& e) const {
  return inverseTransformPoint(model.displacement(action), e.position);
}

TargetState MovingTarget::next(const StateActionModel& model, std::size_t action, const TargetState& e) const {
  const GroundMotion d = model.displacement(action);
  const double seconds = static_cast<double>(model.actionLength(action)) * model.frameTime;
  // The velocity is a direction in the avatar frame: it turns with the frame (by -dyaw) and
  // does not translate; the speed and the turn rate are copied, not recomputed, so they
  // stay on their layers. At turn rate 0 the heading is the straight line's, bit for bit.
  TargetState out(inverseTransformPoint(d, e.at(seconds)), e.speed,
                  std::remainder(e.headingAt(seconds) - d.dyaw, 2 * M_PI));
  out.turnRate = e.turnRate;
  return out;
}

TargetState MovingTarget::draw(const Eigen::Vector3d& position, Rng& rng) const {
  const double speed = minSpeed_ + (motion_.maxSpeed - minSpeed_) * rng.uniform();
  const double heading = (2 * rng.uniform() - 1) * M_PI;
  TargetState e(position, speed, heading);
  // Only a model with turn rates draws one, so straight-line trials keep their random stream.
  if (!motion_.turnRates.empty()) e.turnRate = motion_.turnRates[rng.below(motion_.turnRates.size())];
  return e;
}

}  // namespace mgrl
