#include "mgrl/learning/reward.hpp"

#include <cmath>

namespace mgrl {

Eigen::Vector3d inverseTransformPoint(const GroundMotion& motion, const Eigen::Vector3d& point) {
  // transformPoint maps p to (dx, dz) + R p with R = [[c, s], [-s, c]] on (x, z); invert it.
  const double c = std::cos(motion.dyaw), s = std::sin(motion.dyaw);
  const double qx = point.x() - motion.dx, qz = point.z() - motion.dz;
  return {c * qx - s * qz, point.y(), s * qx + c * qz};
}

Eigen::Vector3d StaticTarget::next(const StateActionModel& model, std::size_t action, const Eigen::Vector3d& e) const {
  return inverseTransformPoint(model.displacement(action), e);
}

}  // namespace mgrl
