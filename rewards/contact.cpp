// term: contact: an effective strike of the effector within `radius` of the target,
// weighted by its speed (the paper's hit reward, sec. 6.4, as a term).
#include <iterator>

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

}  // namespace

void registerContact(TermRegistry& registry) {
  registry.add(
      {"contact",
       "an effective strike of the effector within radius of the target, weighted by its speed",
       {ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                          "which limbs' effective strikes count (feet: effective kicks)"),
        ParamSpec::number("radius", 0.15, 1e-4, 10, "m", "a strike counts when its tip is this close to the target"),
        ParamSpec::boolean("use_speed", true, "weight a strike by its normalised speed (false: 1)"), weightSpec()},
       [](const Params& p) { return std::make_unique<Contact>(p); }});
}

}  // namespace mgrl::rewards
