// term: avoid (issue 17): min(d / clear, 1), d the distance from a body point to the
// nearest tip of the opponent's effective strikes, or the gap between the two bodies if
// smaller. The opponent (environment `opponent`) is an avatar of the same graph standing
// at the target and facing its heading, so its strikes are this model's own.
#include <iterator>
#include <memory>

#include <fmt/format.h>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

/// A learned opponent's strike threatens from this many frames before its effective frame
/// to as many after (the fist near its tip).
constexpr std::uint32_t kStrikeWindow = 2;

class Avoid final : public Term {
 public:
  explicit Avoid(const Params& p)
      : point_(parseBodyPoint(p.choice("point"))),
        effectors_(parseEffector(p.choice("effector"))),
        clear_(p.number("clear")),
        bodyRadius_(p.number("body_radius")) {
    if (point_.kind != BodyPoint::Kind::Joint)
      p.fail("point", fmt::format("expected a role (head, left_fist, ...) or a joint, found {} (the opponent strikes "
                                  "a body joint)",
                                  point_.name));
  }
  void bind(const StateActionModel& m) override {
    bindPoint(m, point_);
    try {
      reach_ = std::make_shared<const StrikeReach>(m, effectors_, clear_);
    } catch (const ConfigError&) {
      throw;
    } catch (const Error& e) {
      throw TermError("effector", e.what());
    }
  }
  double signal(const TermFrame& f) const override {
    // 0 with the body point on a strike tip of the opponent (or the bodies overlapping), 1
    // from `clear` away. The opponent stands where the decision's state has it.
    if (!reach_) throw std::logic_error("an avoid term evaluated before bind()");
    // A learned opponent: only the strikes its action really throws near this frame.
    if (f.opponent)
      return trackedClearance(f.model, f.frame, point_.joint, *f.opponent, effectors_, kStrikeWindow, clear_,
                              bodyRadius_) /
             clear_;
    return opponentClearance(f.model, f.frame, point_.joint, *reach_, f.state, bodyRadius_) / clear_;
  }
  bool readsJoints() const override { return true; }

 private:
  BodyPoint point_;
  std::uint8_t effectors_;
  double clear_, bodyRadius_;
  std::shared_ptr<const StrikeReach> reach_;
};

}  // namespace

void registerAvoid(TermRegistry& registry) {
  registry.add(
      {"avoid",
       "min(d / clear, 1), d the distance from a body point to the nearest tip of the opponent's effective strikes, "
       "or the gap between the two bodies if smaller (the opponent environment: an avatar of the same graph at the "
       "target, facing its heading)",
       {ParamSpec::choiceOrName("point", "head", {"head"}, "a skeleton role or joint",
                                "the body point the opponent must not reach: a role (head, left_shoulder, ...) or a "
                                "joint's name"),
        ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                          "whose strikes the opponent throws (feet: its effective kicks)"),
        ParamSpec::number("clear", 0.3, 0.01, 1, "m", "distance from every strike tip that earns the full signal"),
        ParamSpec::number("body_radius", 0.2, 0, 1, "m",
                          "each body's ground radius: the bodies count as reached when the pelvis is within two of "
                          "them of the opponent (as the world's body_radius)"),
        weightSpec()},
       [](const Params& p) { return std::make_unique<Avoid>(p); }});
}

}  // namespace mgrl::rewards
