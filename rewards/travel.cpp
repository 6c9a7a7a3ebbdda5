// term: travel: clamp(progress / scale_m, 0, 1), the ground progress toward (or away from)
// the target since the decision.
#include <algorithm>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

const BodyPoint kPelvis = BodyPoint::pelvis();

class Travel final : public Term {
 public:
  explicit Travel(const Params& p)
      : scale_(p.choice("direction") == "toward" ? p.number("scale_m") : -p.number("scale_m")) {}
  double signal(const TermFrame& f) const override {
    const double closer = f.startDistance - bodyDistance(f.model, f.frame, kPelvis, 2, f.target);
    return std::clamp(closer / scale_, 0.0, 1.0);
  }

 private:
  double scale_;  ///< m of progress for the full signal; negative when progress is away
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
