// term: distance: exp(-|d - d0| / sigma), d the distance from a body point to the target;
// as a success condition: |d - d0| <= within.
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

// What the term and the condition both read: the point, how d is measured and d0.
struct Measure {
  explicit Measure(const Params& p)
      : point(parseBodyPoint(p.choice("point"))), dims(static_cast<int>(p.integer("dims"))), d0(p.number("d0")) {
    if (point.kind == BodyPoint::Kind::Body)
      p.fail("point", "expected centroid, pelvis, a role or a joint, found body (body is for effort only)");
    if (point.kind == BodyPoint::Kind::Pelvis && dims == 3)
      p.fail("dims", "expected 2 with point: pelvis (a ground point has no height), found 3");
  }
  // |d - d0| at one frame (m).
  double error(const StateActionModel& m, std::size_t frame, const Eigen::Vector3d& target) const {
    return std::abs(bodyDistance(m, frame, point, dims, target) - d0);
  }
  BodyPoint point;
  int dims;
  double d0;
};

ParamSpecs measureSpecs() {
  return {ParamSpec::choiceOrName("point", "centroid", {"centroid", "pelvis"}, "a skeleton role or joint",
                                  "centroid: the effective hitting points' centroid (the paper's); pelvis: the "
                                  "ground point below the root; a role (left_fist, right_toe, head, ...) or a "
                                  "joint's name (LeftHand): that joint"),
          ParamSpec::integer("dims", 2, 2, 3, "", "2: distance on the ground; 3: in space (not with pelvis)"),
          ParamSpec::number("d0", 0, 0, 100, "m", "preferred distance")};
}

class Distance final : public Term {
 public:
  explicit Distance(const Params& p) : measure_(p), sigma_(p.number("sigma")) {}
  void bind(const StateActionModel& m) override { bindPoint(m, measure_.point); }
  double signal(const TermFrame& f) const override {
    return std::exp(-measure_.error(f.model, f.frame, f.target) / sigma_);
  }
  bool readsJoints() const override { return measure_.point.kind == BodyPoint::Kind::Joint; }

 private:
  Measure measure_;
  double sigma_;
};

class DistanceCondition final : public SuccessCondition {
 public:
  explicit DistanceCondition(const Params& p) : measure_(p), within_(p.number("within")) {}
  void bind(const StateActionModel& m) override { bindPoint(m, measure_.point); }
  bool holds(const ConditionFrame& f) const override {
    const BodyPoint& point = measure_.point;
    if (point.kind == BodyPoint::Kind::Joint &&
        (point.joint < 0 || static_cast<std::size_t>(point.joint) >= f.model.jointNames.size()))
      throw std::logic_error("a success condition naming a joint used before bind()");
    return !(measure_.error(f.model, f.frame, f.target.position) > within_);  // as the enum did (NaN holds)
  }
  nlohmann::json toJson() const override {
    return {{"term", "distance"},
            {"point", bodyPointName(measure_.point)},
            {"dims", measure_.dims},
            {"d0", measure_.d0},
            {"within", within_}};
  }
  std::string describe() const override {
    return fmt::format("the {} within {:g} m of {:g} m from the target{}", bodyPointName(measure_.point), within_,
                       measure_.d0, measure_.dims == 3 ? " (3-D)" : "");
  }

 private:
  Measure measure_;
  double within_;
};

}  // namespace

void registerDistance(Vocabulary& v) {
  ParamSpecs term = measureSpecs();
  term.push_back(ParamSpec::number("sigma", 0.1, 1e-4, 100, "m", "distance scale of the exponential"));
  term.push_back(weightSpec());
  v.terms.add({"distance", "exp(-|d - d0| / sigma), d the distance from a body point to the target", std::move(term),
               [](const Params& p) { return std::make_unique<Distance>(p); }});
  ParamSpecs condition = measureSpecs();
  condition.push_back(ParamSpec::number("within", 0.2, 0, 100, "m", "the threshold on |d - d0|"));
  ConditionRegistry::Entry entry{"distance", "|d - d0| <= within (m), d as the reward's distance term measures it",
                                 std::move(condition),
                                 [](const Params& p) { return std::make_unique<DistanceCondition>(p); }};
  entry.inherited = {"point", "dims", "d0"};
  v.conditions.add(std::move(entry));
}

}  // namespace mgrl::rewards
