// term: struck, a cost: s, the opponent's strike landing on a body point at frame
// t (its speed weight, or 1), 0 when none lands; the reward subtracts w s. `contact` seen
// from the other side: with the same weight and radius as the behaviour's contact, a punch
// landed and a punch taken cancel, so a best response against a fixed opponent (self-play
// rounds) is paid for trading well, not for trading at all. (A reward of 1 - s would do the
// same for value iteration, but it would lift every value by w / (1 - gamma) and make the
// world's variety margin, a share of the best value, keep every candidate.)
#include <algorithm>
#include <iterator>
#include <memory>
#include <stdexcept>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

class Struck final : public Term {
 public:
  explicit Struck(const Params& p)
      : point_(struckPoint(p)),
        effectors_(parseEffector(p.choice("effector"))),
        radius_(p.number("radius")),
        useSpeed_(p.boolean("use_speed")),
        bodyRadius_(p.number("body_radius")) {}
  void bind(const StateActionModel& m) override {
    bindPoint(m, point_);
    reach_ = bindReach(m, effectors_, std::min(1.0, radius_ + 0.05));
  }
  double signal(const TermFrame& f) const override {
    if (!reach_) throw std::logic_error("a struck term evaluated before bind()");
    // A learned opponent: the strikes its action throws at exactly this frame (the world
    // checks a strike at its effective frame only, paper sec. 6.6).
    if (f.opponent) return trackedStrikeAt(f.model, f.frame, point_.joint, *f.opponent, effectors_, radius_, useSpeed_);
    // The scripted opponent of `opponent` throws every strike of the graph at every moment:
    // any tip within the radius lands.
    const double d = opponentClearance(f.model, f.frame, point_.joint, *reach_, f.state, bodyRadius_);
    return d <= radius_ ? 1.0 : 0.0;
  }
  bool readsJoints() const override { return true; }
  bool cost() const override { return true; }

 private:
  BodyPoint point_;
  std::uint8_t effectors_;
  double radius_;
  bool useSpeed_;
  double bodyRadius_;
  std::shared_ptr<const StrikeReach> reach_;
};

}  // namespace

void registerStruck(Vocabulary& v) {
  v.terms.add(
      {"struck",
       "a cost (the reward subtracts w s): s the speed weight (or 1) of the opponent's effective strike landing "
       "within radius of a body point at this frame, 0 if none; contact taken rather than given (a learned "
       "opponent's actual strikes; the scripted opponent's every strike)",
       {ParamSpec::choiceOrName("point", "head", {"head"}, "a skeleton role or joint",
                                "the body point the opponent's strike lands on: a role (head, ...) or a joint's name"),
        ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                          "whose strikes the opponent throws (feet: its effective kicks)"),
        ParamSpec::number("radius", 0.15, 1e-4, 0.95, "m", "a strike lands when its tip is this close to the point"),
        ParamSpec::boolean("use_speed", true, "weight a strike by its normalised speed (false: 1)"),
        ParamSpec::number("body_radius", 0.2, 0, 1, "m",
                          "the scripted opponent: each body's ground radius (bodies overlapping count as struck)"),
        weightSpec()},
       [](const Params& p) { return std::make_unique<Struck>(p); }});
}

}  // namespace mgrl::rewards
