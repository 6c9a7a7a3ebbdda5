// term: avoid: min(d / clear, 1), d the distance from a body point to the
// nearest tip of the opponent's effective strikes, or the gap between the two bodies if
// smaller. The opponent (environment `opponent`) is an avatar of the same graph standing
// at the target and facing its heading, so its strikes are this model's own.
#include <algorithm>
#include <iterator>
#include <memory>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

/// A learned opponent's strike threatens from this many frames before its effective frame
/// to as many after (the fist near its tip).
constexpr std::uint32_t kStrikeWindow = 2;

// What the term and the condition both read: the body point the opponent must not reach,
// whose strikes, the clearance and the bodies' radius, and, once bound, where the strikes
// reach (a field capped at `cap`).
struct Guard {
  explicit Guard(const Params& p)
      : point(struckPoint(p)),
        effectors(parseEffector(p.choice("effector"))),
        clear(p.number("clear")),
        bodyRadius(p.number("body_radius")) {}
  void bind(const StateActionModel& m, double cap) {
    bindPoint(m, point);
    reach = bindReach(m, effectors, cap);
  }
  BodyPoint point;
  std::uint8_t effectors;
  double clear, bodyRadius;
  std::shared_ptr<const StrikeReach> reach;
};

class Avoid final : public Term {
 public:
  explicit Avoid(const Params& p) : guard_(p) {}
  void bind(const StateActionModel& m) override { guard_.bind(m, guard_.clear); }
  double signal(const TermFrame& f) const override {
    // 0 with the body point on a strike tip of the opponent (or the bodies overlapping), 1
    // from `clear` away. The opponent stands where the decision's state has it.
    const Guard& g = guard_;
    if (!g.reach) throw std::logic_error("an avoid term evaluated before bind()");
    // A learned opponent: only the strikes its action really throws near this frame.
    if (f.opponent)
      return trackedClearance(f.model, f.frame, g.point.joint, *f.opponent, g.effectors, kStrikeWindow, g.clear,
                              g.bodyRadius) /
             g.clear;
    return opponentClearance(f.model, f.frame, g.point.joint, *g.reach, f.state, g.bodyRadius) / g.clear;
  }
  bool readsJoints() const override { return true; }

 private:
  Guard guard_;
};

// As a success condition: the point at least `clear` from every strike tip the opponent
// standing at the target can throw (a learned opponent: those it throws near the frame),
// and the bodies at least `clear` apart.
class AvoidCondition final : public SuccessCondition {
 public:
  explicit AvoidCondition(const Params& p) : guard_(p) {}
  // The opponent is an avatar of this graph: its strikes are this model's. The field
  // reaches a little past `clear` so "at least clear" is read from exact distances.
  void bind(const StateActionModel& m) override { guard_.bind(m, std::min(1.0, guard_.clear + 0.05)); }
  bool holds(const ConditionFrame& f) const override {
    const Guard& g = guard_;
    if (!g.reach || g.point.joint < 0 || static_cast<std::size_t>(g.point.joint) >= f.model.jointNames.size())
      throw std::logic_error("an avoid success condition used before bind()");
    // A learned opponent: the strikes it throws near this frame, as the term reads them.
    if (f.opponent)
      return !(trackedClearance(f.model, f.frame, g.point.joint, *f.opponent, g.effectors, kStrikeWindow,
                                g.reach->cap(), g.bodyRadius) < g.clear);
    return !(opponentClearance(f.model, f.frame, g.point.joint, *g.reach, f.target, g.bodyRadius) < g.clear);
  }
  nlohmann::json toJson() const override {
    return {{"term", "avoid"},
            {"point", bodyPointName(guard_.point)},
            {"effectors", guard_.effectors},
            {"clear", guard_.clear},
            {"body_radius", guard_.bodyRadius}};
  }
  std::string describe() const override {
    return fmt::format("the {} at least {:g} m from the opponent's strikes and body", bodyPointName(guard_.point),
                       guard_.clear);
  }
  std::optional<Clearance> clearance() const override {
    return Clearance{guard_.point.joint, guard_.effectors, guard_.clear, guard_.bodyRadius};
  }

 private:
  Guard guard_;
};

}  // namespace

void registerAvoid(Vocabulary& v) {
  const ParamSpec point = ParamSpec::choiceOrName(
      "point", "head", {"head"}, "a skeleton role or joint",
      "the body point the opponent must not reach: a role (head, left_shoulder, ...) or a joint's name");
  const ParamSpec effector =
      ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                        "whose strikes the opponent throws (feet: its effective kicks)");
  const ParamSpec bodyRadius =
      ParamSpec::number("body_radius", 0.2, 0, 1, "m",
                        "each body's ground radius: the bodies count as reached when the "
                        "pelvis is within two of them of the opponent (as the world's body_radius)");
  v.terms.add(
      {"avoid",
       "min(d / clear, 1), d the distance from a body point to the nearest tip of the opponent's effective strikes, "
       "or the gap between the two bodies if smaller (the opponent environment: an avatar of the same graph at the "
       "target, facing its heading)",
       {point, effector,
        ParamSpec::number("clear", 0.3, 0.01, 1, "m", "distance from every strike tip that earns the full signal"),
        bodyRadius, weightSpec()},
       [](const Params& p) { return std::make_unique<Avoid>(p); }});
  // The condition's `clear` is its threshold, not the term's scale: not inherited.
  ConditionRegistry::Entry entry{
      "avoid",
      "d >= clear, d as the avoid term measures it (the point out of the opponent's strikes and the bodies apart)",
      {point, effector, ParamSpec::number("clear", 0.1, 0, 0.95, "m", "the threshold on d"), bodyRadius},
      [](const Params& p) { return std::make_unique<AvoidCondition>(p); }};
  entry.inherited = {"point", "effector", "body_radius"};
  v.conditions.add(std::move(entry));
}

}  // namespace mgrl::rewards
