// term: travel: clamp(progress / scale_m, 0, 1), the ground progress toward (or away from)
// the target since the decision.
#include <algorithm>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

const BodyPoint kPelvis = BodyPoint::pelvis();

class Travel final : public Term {
 public:
  explicit Travel(const Params& p) : sign_(p.choice("direction") == "toward" ? 1 : -1), scale_(p.number("scale_m")) {}
  double signal(const TermFrame& f) const override {
    const double progress = sign_ * (f.startDistance - bodyDistance(f.model, f.frame, kPelvis, 2, f.target));
    return std::clamp(progress / scale_, 0.0, 1.0);
  }

 private:
  int sign_;
  double scale_;
};

}  // namespace

void registerTravel(Vocabulary& v) {
  v.terms.add({"travel",
               "clamp(progress / scale_m, 0, 1): ground progress toward (or away from) the target since the decision",
               {ParamSpec::choice("direction", "toward", {"toward", "away"}, "which way counts as progress"),
                ParamSpec::number("scale_m", 1, 1e-3, 100, "m", "progress that earns the full signal"), weightSpec()},
               [](const Params& p) { return std::make_unique<Travel>(p); }});
}

}  // namespace mgrl::rewards
