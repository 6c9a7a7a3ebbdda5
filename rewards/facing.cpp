// term: facing: exp(-|angle - angle0| / sigma), the angle between the avatar's facing and
// the target's direction.
#include <cmath>
#include <numbers>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

constexpr double kDegree = std::numbers::pi / 180;

class Facing final : public Term {
 public:
  explicit Facing(const Params& p) : angle_(p.number("angle_deg") * kDegree), sigma_(p.number("sigma_deg") * kDegree) {}
  double signal(const TermFrame& f) const override {
    return std::exp(-std::abs(facingError(f.model, f.frame, f.target) - angle_) / sigma_);
  }

 private:
  double angle_, sigma_;  // rad
};

}  // namespace

void registerFacing(TermRegistry& registry) {
  registry.add({"facing",
                "exp(-|angle - angle0| / sigma), angle between the avatar's facing and the target's direction",
                {ParamSpec::number("angle_deg", 0, 0, 180, "deg", "preferred angle (0: target straight ahead)"),
                 ParamSpec::number("sigma_deg", 30, 0.1, 360, "deg", "angle scale of the exponential"), weightSpec()},
                [](const Params& p) { return std::make_unique<Facing>(p); }});
}

}  // namespace mgrl::rewards
