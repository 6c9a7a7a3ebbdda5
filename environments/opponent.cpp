// opponent (Lee & Lee sec. 7's next step, "sparring with a real opponent instead
// of a static target"): the target is another avatar of the same graph. Its state in the
// avatar frame is where it stands and which way it faces (TargetState::position on the
// ground, ::heading; speed 0). Between decisions it plays a fixed policy:
//   pursue: walk toward the avatar at `speed` until `stop_distance` from it, turning to
//           face it at up to `turn_rate`;
//   stand:  stay put, turning to face the avatar.
// Its strikes are the graph's own effective strikes around it (StrikeReach); the `avoid`
// term and success condition read them. The update is exact and deterministic, so
// value iteration can tabulate it: the opponent's pose changes at the end of each of the
// avatar's actions (sample and hold), from the avatar's pose at that end.
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "environments.hpp"

namespace mgrl::environments {

TargetState Opponent::next(const StateActionModel& model, std::size_t action, const TargetState& e) const {
  const GroundMotion d = model.displacement(action);
  const double seconds = static_cast<double>(model.actionLength(action)) * model.frameTime;
  // In the decision's frame: the avatar ends at (d.dx, d.dz); the opponent steps toward it
  // (pursue) and turns toward where it ends.
  double ox = e.position.x(), oz = e.position.z();
  double tx = d.dx - ox, tz = d.dz - oz;
  const double gap = std::hypot(tx, tz);
  if (!scripted_.stand && gap > scripted_.stopDistance) {
    const double step = std::min(speed_ * seconds, gap - scripted_.stopDistance);
    ox += step * tx / gap;
    oz += step * tz / gap;
    tx = d.dx - ox;
    tz = d.dz - oz;
  }
  double facing = e.heading;
  if (tx != 0 || tz != 0) {
    const double turn = std::remainder(std::atan2(tx, tz) - facing, 2 * M_PI);
    const double most = turnRate_ * seconds;
    facing += std::clamp(turn, -most, most);
  }
  // Seen from the action's end, as the static target is.
  return {inverseTransformPoint(d, Eigen::Vector3d(ox, e.position.y(), oz)), 0.0,
          std::remainder(facing - d.dyaw, 2 * M_PI)};
}

TargetState Opponent::draw(const Eigen::Vector3d& position, Rng&) const {
  // A trial's opponent starts facing the avatar, as sparring partners do.
  return {position, 0.0, std::atan2(-position.x(), -position.z())};
}

void registerOpponent(EnvironmentRegistry& registry) {
  registry.add({"opponent",
                "the target is another avatar of the same graph: its ground position and facing (the grid's heading) "
                "are the state; it walks toward the avatar (policy: pursue) or stands (stand), turning to face it; its "
                "strikes are the graph's own (the avoid term)",
                {ParamSpec::choice("policy", "pursue", {"pursue", "stand"},
                                   "pursue: walk toward the avatar until stop_distance; stand: stay put; both turn "
                                   "to face it"),
                 ParamSpec::number("speed", 0.3, 0, 5, "m/s",
                                   "pursue: walking speed (the boxing capture's median ground speed per action is "
                                   "0.24 m/s)"),
                 ParamSpec::number("stop_distance", 0.7, 0, 10, "m", "pursue: stops this far from the avatar (ground)"),
                 ParamSpec::number("turn_rate", 120, 0, 3600, "deg/s", "how fast it turns to face the avatar")},
                [](const Params& p) {
                  return std::make_unique<Opponent>(p.choice("policy") == "pursue", p.number("speed"),
                                                    p.number("stop_distance"), p.number("turn_rate") * M_PI / 180);
                }});
}

}  // namespace mgrl::environments
