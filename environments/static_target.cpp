// static_target (Lee & Lee sec. 4.1): the target stays put in the world, so after an
// action it is seen from the action's end through the inverse of the action's root
// displacement: exact, no sampling. moving_target: a straight line at a constant
// velocity, or an arc at a constant turn rate, exact like the static one
// (framework/learning/environment_model.cpp).
#include <cmath>
#include <memory>
#include <vector>

#include <fmt/format.h>

#include "environments.hpp"

namespace mgrl::environments {

void registerStaticTargets(EnvironmentRegistry& registry) {
  registry.add({"static_target",
                "the target stays put in the world; after an action it is seen from the action's end (exact)",
                {},
                [](const Params&) { return std::make_unique<StaticTarget>(); }});
  registry.add({"moving_target",
                "the target moves on the ground at a speed drawn per episode from [min_speed, max_speed] in a "
                "uniform direction, in a straight line or, with max_turn_deg_s, round a circle at one of `turns` "
                "turn rates; its speed and heading in the avatar frame are part of the state (pair it with a grid "
                "that has them, e.g. polar_velocity), which then gets one layer per turn rate",
                {ParamSpec::number("min_speed", 0.0, 0, 20, "m/s", "slowest target an evaluation trial draws"),
                 ParamSpec::number("max_speed", 1.0, 0, 20, "m/s", "fastest target an evaluation trial draws"),
                 ParamSpec::number("max_turn_deg_s", 0.0, 0, 720, "deg/s",
                                   "fastest turn of a target's path (0: straight lines only); an episode draws "
                                   "one of `turns` rates evenly spaced from -max_turn_deg_s to +max_turn_deg_s"),
                 ParamSpec::integer("turns", 3, 1, 101, "rates",
                                    "turn rates (grid layers) with max_turn_deg_s > 0; odd counts include 0, a "
                                    "straight line")},
                [](const Params& p) {
                  const double lo = p.number("min_speed"), hi = p.number("max_speed");
                  if (lo > hi)
                    p.fail("min_speed", fmt::format("expected at most max_speed ({} m/s), found {} m/s", hi, lo));
                  const double turn = p.number("max_turn_deg_s") * M_PI / 180;
                  const auto turns = static_cast<std::size_t>(p.integer("turns"));
                  if (turn == 0) return std::make_unique<MovingTarget>(lo, hi);
                  if (turns < 2)
                    p.fail("turns", fmt::format("expected at least 2 turn rates with max_turn_deg_s {} (from -{} to "
                                                "+{} deg/s), found {}",
                                                p.number("max_turn_deg_s"), p.number("max_turn_deg_s"),
                                                p.number("max_turn_deg_s"), turns));
                  std::vector<double> rates(turns);
                  for (std::size_t k = 0; k < turns; ++k)
                    rates[k] = -turn + 2 * turn * static_cast<double>(k) / static_cast<double>(turns - 1);
                  if (turns % 2 == 1) rates[turns / 2] = 0;  // exactly straight, not a rounding residue
                  return std::make_unique<MovingTarget>(lo, hi, std::move(rates));
                }});
}

}  // namespace mgrl::environments
