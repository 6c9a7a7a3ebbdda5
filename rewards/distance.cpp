// term: distance: exp(-|d - d0| / sigma), d the distance from a body point to the target.
#include <cmath>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

class Distance final : public Term {
 public:
  explicit Distance(const Params& p)
      : point_(parseBodyPoint(p.choice("point"))),
        dims_(static_cast<int>(p.integer("dims"))),
        d0_(p.number("d0")),
        sigma_(p.number("sigma")) {
    if (point_.kind == BodyPoint::Kind::Body)
      p.fail("point", "expected centroid, pelvis, a role or a joint, found body (body is for effort only)");
    if (point_.kind == BodyPoint::Kind::Pelvis && dims_ == 3)
      p.fail("dims", "expected 2 with point: pelvis (a ground point has no height), found 3");
  }
  void bind(const StateActionModel& m) override { bindPoint(m, point_); }
  double signal(const TermFrame& f) const override {
    return std::exp(-std::abs(bodyDistance(f.model, f.frame, point_, dims_, f.target) - d0_) / sigma_);
  }
  bool readsJoints() const override { return point_.kind == BodyPoint::Kind::Joint; }

 private:
  BodyPoint point_;
  int dims_;
  double d0_, sigma_;
};

}  // namespace

void registerDistance(TermRegistry& registry) {
  registry.add({"distance",
                "exp(-|d - d0| / sigma), d the distance from a body point to the target",
                {ParamSpec::choiceOrName("point", "centroid", {"centroid", "pelvis"}, "a skeleton role or joint",
                                         "centroid: the effective hitting points' centroid (the paper's); pelvis: the "
                                         "ground point below the root; a role (left_fist, right_toe, head, ...) or a "
                                         "joint's name (LeftHand): that joint"),
                 ParamSpec::integer("dims", 2, 2, 3, "", "2: distance on the ground; 3: in space (not with pelvis)"),
                 ParamSpec::number("d0", 0, 0, 100, "m", "preferred distance"),
                 ParamSpec::number("sigma", 0.1, 1e-4, 100, "m", "distance scale of the exponential"), weightSpec()},
                [](const Params& p) { return std::make_unique<Distance>(p); }});
}

}  // namespace mgrl::rewards
