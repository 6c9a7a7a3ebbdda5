// term: facing: how the avatar's facing stands to the target's direction. Either
// exp(-|angle - angle0| / sigma) about a given angle, or (prefer: hits) the capture's own
// stance: how often the source's effective strikes land at that signed angle from the
// facing, a density normalised to 1 at its mode (issue 46: a boxer whose punches land 30
// degrees to his left stands with his target there, not straight ahead). As a success
// condition: |angle - angle0| <= within_deg.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <set>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

constexpr double kDegree = std::numbers::pi / 180;

class Facing final : public Term {
 public:
  explicit Facing(const Params& p) : angle_(p.number("angle_deg") * kDegree), sigma_(p.number("sigma_deg") * kDegree) {}
  double signal(const TermFrame& f) const override {
    return std::exp(-std::abs(facingError(f.model, f.frame, f.target) - angle_) / sigma_);
  }

 private:
  double angle_, sigma_;  // rad
};

class FacingCondition final : public SuccessCondition {
 public:
  explicit FacingCondition(const Params& p)
      : angle_(p.number("angle_deg") * kDegree), within_(p.number("within_deg") * kDegree) {}
  bool holds(const ConditionFrame& f) const override {
    return !(std::abs(facingError(f.model, f.frame, f.target.position) - angle_) > within_);
  }
  nlohmann::json toJson() const override {
    return {{"term", "facing"}, {"angle_deg", angle_ / kDegree}, {"within_deg", within_ / kDegree}};
  }
  std::string describe() const override {
    return fmt::format("facing within {:g} deg of {:g} deg off the target", within_ / kDegree, angle_ / kDegree);
  }

 private:
  double angle_, within_;  // rad
};

// The density of the signed angle, on the ground, from the avatar's facing to its own
// effective hitting points (punches and kicks) at their frames: one sample per source frame
// and limb (an action replaying a frame adds none), smoothed with a circular Gaussian of
// `sigma`, tabulated per degree and normalised to 1 at its largest.
class HitFacing final : public Term {
 public:
  explicit HitFacing(const Params& p) : sigma_(p.number("sigma_deg")) {}

  void bind(const StateActionModel& m) override {
    std::array<double, kBins> counts{};
    std::set<std::pair<std::uint32_t, std::uint8_t>> seen;  // (source frame, limb)
    std::size_t samples = 0;
    auto add = [&](const std::vector<ActionHit>& list, std::uint8_t limb0) {
      for (const ActionHit& h : list) {
        const std::size_t k = m.actionFrameBegin[h.action] + h.offset - 1;
        if (!seen.emplace(m.actionFrames[k], static_cast<std::uint8_t>(limb0 + h.hand)).second) continue;
        const double angle = signedFacing(m, k, Eigen::Vector3d(h.x, h.y, h.z)) / kDegree;  // (-180, 180]
        counts[static_cast<std::size_t>(std::lround(angle + 180)) % kBins] += 1;
        ++samples;
      }
    };
    add(m.hits, 0);
    add(m.kicks, 2);
    if (samples == 0)
      throw TermError("prefer",
                      "expected effective punches or kicks in the capture to learn the facing from (prefer: "
                      "hits), found none; use prefer: angle with angle_deg");
    // Circular Gaussian smoothing (kernel cut at 4 sigma).
    const int reach = static_cast<int>(std::ceil(4 * sigma_));
    double largest = 0;
    for (int b = 0; b < static_cast<int>(kBins); ++b) {
      double sum = 0;
      for (int d = -reach; d <= reach; ++d)
        sum += counts[static_cast<std::size_t>(((b + d) % kBins + kBins) % kBins)] *
               std::exp(-0.5 * (d / sigma_) * (d / sigma_));
      density_[static_cast<std::size_t>(b)] = sum;
      largest = std::max(largest, sum);
    }
    for (double& d : density_) d /= largest;
    bound_ = true;
  }

  double signal(const TermFrame& f) const override {
    if (!bound_) throw std::logic_error("facing term with prefer: hits evaluated before it was bound to a model");
    const double degrees = signedFacing(f.model, f.frame, f.target) / kDegree + 180;  // [0, 360]
    const double low = std::floor(degrees), w = degrees - low;
    const auto a = static_cast<std::size_t>(low) % kBins, b = (a + 1) % kBins;
    return (1 - w) * density_[a] + w * density_[b];
  }

 private:
  static constexpr int kBins = 360;  // one per degree, bin b at b - 180 degrees
  double sigma_;                     // degrees
  std::array<double, kBins> density_{};
  bool bound_ = false;
};

}  // namespace

void registerFacing(Vocabulary& v) {
  const ParamSpec angle =
      ParamSpec::number("angle_deg", 0, 0, 180, "deg", "preferred angle (0: target straight ahead)");
  v.terms.add(
      {"facing",
       "exp(-|angle - angle0| / sigma), angle between the avatar's facing and the target's direction; or "
       "(prefer: hits) how often the capture's own strikes land at that signed angle",
       {ParamSpec::choice("prefer", "angle", {"angle", "hits"},
                          "angle: about angle_deg; hits: the capture's distribution of the signed angle from "
                          "the facing to its effective hitting points (its own stance), smoothed by sigma_deg"),
        angle, ParamSpec::number("sigma_deg", 30, 0.1, 360, "deg", "angle scale of the exponential (of the smoothing)"),
        weightSpec()},
       [](const Params& p) -> std::unique_ptr<Term> {
         if (p.choice("prefer") == "hits") return std::make_unique<HitFacing>(p);
         return std::make_unique<Facing>(p);
       }});
  ConditionRegistry::Entry entry{
      "facing",
      "|angle - angle0| <= within_deg, angle between the avatar's facing and the target's direction",
      {angle, ParamSpec::number("within_deg", 30, 0, 180, "deg", "the threshold on |angle - angle0|")},
      [](const Params& p) { return std::make_unique<FacingCondition>(p); }};
  entry.inherited = {"angle_deg"};
  v.conditions.add(std::move(entry));
}

}  // namespace mgrl::rewards
