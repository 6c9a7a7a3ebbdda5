// term: effort: exp(-v / speed_mps), v the avatar's ground speed or a joint's speed:
// economy; standing still earns 1.
#include <cmath>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

class Effort final : public Term {
 public:
  explicit Effort(const Params& p) : point_(parseBodyPoint(p.choice("point"))), speed_(p.number("speed_mps")) {
    if (point_.kind == BodyPoint::Kind::Centroid)
      p.fail("point",
             "expected pelvis (root speed), body (every joint's mean speed), a role or a joint, found "
             "centroid (the centroid is carried along rigidly; its speed is the root's)");
  }
  void bind(const StateActionModel& m) override { bindPoint(m, point_); }
  double signal(const TermFrame& f) const override {
    const double v = point_.kind == BodyPoint::Kind::Pelvis ? rootSpeed(f.model, f.action, f.t)
                                                            : bodySpeed(f.model, f.frame, point_);
    return std::exp(-v / speed_);
  }
  bool readsJoints() const override {
    return point_.kind == BodyPoint::Kind::Joint || point_.kind == BodyPoint::Kind::Body;
  }

 private:
  BodyPoint point_;
  double speed_;
};

}  // namespace

void registerEffort(Vocabulary& v) {
  v.terms.add({"effort",
               "exp(-v / speed_mps), v the avatar's ground speed or a joint's speed: economy, standing still earns 1",
               {ParamSpec::number("speed_mps", 1, 1e-3, 100, "m/s", "speed scale of the exponential"),
                ParamSpec::choiceOrName("point", "pelvis", {"pelvis", "body"}, "a skeleton role or joint",
                                        "pelvis: the root's ground speed; body: the mean speed of every joint in the "
                                        "capture; a role or a joint's name: that joint's speed"),
                weightSpec()},
               [](const Params& p) { return std::make_unique<Effort>(p); }});
}

}  // namespace mgrl::rewards
