// static_target (Lee & Lee sec. 4.1): the target stays put in the world, so after an
// action it is seen from the action's end through the inverse of the action's root
// displacement: exact, no sampling. moving_target (issue 17): a straight line at a constant
// velocity, exact like the static one (framework/learning/reward.cpp).
#include <memory>

#include <fmt/format.h>

#include "environments.hpp"

namespace mgrl::environments {

void registerStaticTargets(EnvironmentRegistry& registry) {
  registry.add({"static_target",
                "the target stays put in the world; after an action it is seen from the action's end (exact)",
                {},
                [](const Params&) { return std::make_unique<StaticTarget>(); }});
  registry.add({"moving_target",
                "the target moves on the ground in a straight line at a speed drawn per episode from [min_speed, "
                "max_speed] in a uniform direction; its speed and heading in the avatar frame are part of the state "
                "(pair it with a grid that has them, e.g. polar_velocity)",
                {ParamSpec::number("min_speed", 0.0, 0, 20, "m/s", "slowest target an evaluation trial draws"),
                 ParamSpec::number("max_speed", 1.0, 0, 20, "m/s", "fastest target an evaluation trial draws")},
                [](const Params& p) {
                  const double lo = p.number("min_speed"), hi = p.number("max_speed");
                  if (lo > hi) p.fail("min_speed", fmt::format("expected at most max_speed ({} m/s), found {} m/s", hi, lo));
                  return std::make_unique<MovingTarget>(lo, hi);
                }});
}

}  // namespace mgrl::environments
