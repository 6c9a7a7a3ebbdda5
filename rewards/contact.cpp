// term: contact: an effective strike of the effector within `radius` of the target,
// weighted by its speed (the paper's hit reward, sec. 6.4, as a term); as a success
// condition: such a strike lands (the paper's hit).
#include <iterator>
#include <utility>

#include <fmt/format.h>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

class Contact final : public Term {
 public:
  explicit Contact(const Params& p)
      : effectors_(parseEffector(p.choice("effector"))),
        radius_(p.number("radius")),
        useSpeed_(p.boolean("use_speed")) {}
  double signal(const TermFrame& f) const override {
    return strikeAt(f.model, f.action, static_cast<std::uint32_t>(f.t), effectors_, radius_, useSpeed_, f.target);
  }

 private:
  std::uint8_t effectors_;
  double radius_;
  bool useSpeed_;
};

class ContactCondition final : public SuccessCondition {
 public:
  explicit ContactCondition(const Params& p)
      : effectors_(parseEffector(p.choice("effector"))), radius_(p.number("radius")) {}
  bool holds(const ConditionFrame& f) const override {
    return strikeAt(f.model, f.action, f.t, effectors_, radius_, false, f.target.position) > 0;
  }
  bool instant() const override { return true; }
  nlohmann::json toJson() const override {
    return {{"term", "contact"}, {"effectors", effectors_}, {"radius", radius_}};
  }
  std::string describe() const override {
    static const std::pair<std::uint8_t, const char*> kNames[] = {
        {kAnyLimb, "any limb"},        {kFists, "the fists"},          {kFeet, "the feet"},
        {kLeftFist, "the left fist"},  {kRightFist, "the right fist"}, {kLeftFoot, "the left foot"},
        {kRightFoot, "the right foot"}};
    std::string who = "some limbs";
    for (const auto& [bits, name] : kNames)
      if (bits == effectors_) who = name;
    return fmt::format("an effective strike of {} within {:g} m", who, radius_);
  }

 private:
  std::uint8_t effectors_;
  double radius_;
};

ParamSpecs strikeSpecs() {
  return {ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                            "which limbs' effective strikes count (feet: effective kicks)"),
          ParamSpec::number("radius", 0.15, 1e-4, 10, "m", "a strike counts when its tip is this close to the target")};
}

}  // namespace

void registerContact(Vocabulary& v) {
  ParamSpecs term = strikeSpecs();
  term.push_back(ParamSpec::boolean("use_speed", true, "weight a strike by its normalised speed (false: 1)"));
  term.push_back(weightSpec());
  v.terms.add({"contact", "an effective strike of the effector within radius of the target, weighted by its speed",
               std::move(term), [](const Params& p) { return std::make_unique<Contact>(p); }});
  ConditionRegistry::Entry entry{"contact", "an effective strike of the effector lands within radius of the target",
                                 strikeSpecs(), [](const Params& p) { return std::make_unique<ContactCondition>(p); }};
  entry.inherited = {"effector", "radius"};
  v.conditions.add(std::move(entry));
}

}  // namespace mgrl::rewards
