// The boxing rewards (paper sec. 6.4). approach: r = max_t gamma^t exp(-|p(t) - p_d| / sigma),
// p(t) the ground position of the centroid of the effective hitting points carried along
// with the avatar, p_d the target's; t counts frames after the decision (1 = the first).
#include <cmath>

#include "rewards.hpp"

namespace mgrl::rewards {

namespace {

class Approach final : public Reward {
 public:
  explicit Approach(const Params& p) : sigma_(p.number("sigma")), gamma_(p.number("gamma")) {}
  std::string type() const override { return "approach"; }
  double gamma() const override { return gamma_; }
  double evaluate(const StateActionModel& m, std::size_t a, const TargetState& state) const override {
    const std::size_t begin = m.actionFrameBegin[a], frames = m.actionLength(a);
    const float* p = &m.frameCentroid[3 * begin];
    double best = 0, discount = 1;
    for (std::size_t t = 1; t <= frames; ++t, p += 3) {
      discount *= gamma_;
      const Eigen::Vector3d e = state.at(static_cast<double>(t) * m.frameTime);  // a moving target is where it is then
      const double distance = std::hypot(p[0] - e.x(), p[2] - e.z());
      best = std::max(best, discount * std::exp(-distance / sigma_));
    }
    return best;
  }
  // The centroid's ground distance to the target (sec. 6.4) as a distance term.
  nlohmann::json terms() const override {
    return nlohmann::json::array({{{"term", "distance"}, {"point", "centroid"}, {"dims", 2}, {"d0", 0}}});
  }

 private:
  double sigma_, gamma_;
};

class Hit final : public Reward {
 public:
  explicit Hit(const Params& p)
      : radius_(p.number("contact_radius")), gamma_(p.number("gamma")), useSpeed_(p.boolean("use_speed")) {}
  std::string type() const override { return "hit"; }
  double gamma() const override { return gamma_; }
  // r = max_t gamma^t I(t) w(t) (paper sec. 6.4): I(t) = 1 where an effective hit lands
  // within contact_radius of the target, w(t) the fist speed normalised to the fastest hit.
  double evaluate(const StateActionModel& m, std::size_t a, const TargetState& state) const override {
    double best = 0;
    for (const ActionHit& h : m.hitsOf(a)) {
      const Eigen::Vector3d e = state.at(h.offset * m.frameTime);
      const double dx = h.x - e.x(), dy = h.y - e.y(), dz = h.z - e.z();
      if (dx * dx + dy * dy + dz * dz > radius_ * radius_) continue;
      best = std::max(best, std::pow(gamma_, h.offset) * (useSpeed_ ? h.weight : 1.0));
    }
    return best;
  }
  nlohmann::json terms() const override {
    return nlohmann::json::array({{{"term", "contact"}, {"effector", "fists"}, {"radius", radius_}}});
  }

 private:
  double radius_, gamma_;
  bool useSpeed_;
};

ParamSpec gammaSpec() {
  return ParamSpec::number("gamma", 0.97, 1e-6, 1, "per frame", "discount per frame, inside and after the action");
}

}  // namespace

void registerPaperRewards(RewardRegistry& registry) {
  registry.add({"approach",
                "max over the action's frames of gamma^t exp(-|p(t) - target| / sigma), p the ground position of "
                "the effective hitting points' centroid (paper sec. 6.4)",
                {ParamSpec::number("sigma", 0.10, 1e-4, 100, "m", "distance scale of the exponential"), gammaSpec()},
                [](const Params& p) { return std::make_unique<Approach>(p); }});
  registry.add({"hit",
                "max over the action's effective hits within contact_radius of the target of gamma^t w, w the fist "
                "speed normalised to the fastest hit (paper sec. 6.4)",
                {ParamSpec::number("contact_radius", 0.15, 1e-4, 10, "m",
                                   "a hit counts when the fist tip is this close to the target point"),
                 gammaSpec(),
                 ParamSpec::boolean("use_speed", true, "weight a hit by its normalised fist speed (false: 1)")},
                [](const Params& p) { return std::make_unique<Hit>(p); }});
}

}  // namespace mgrl::rewards
