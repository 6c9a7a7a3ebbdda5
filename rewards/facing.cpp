// term: facing: how the avatar's facing stands to the target's direction. Either
// exp(-|angle - angle0| / sigma) about a given angle, or a stance learned from capture, a
// density normalised to 1 at its mode: (prefer: hits) how often the source's
// effective strikes land at that signed angle from the facing (a boxer whose punches land
// 30 degrees to his left stands with his target there, not straight ahead), or (prefer:
// bouts) how often the real SNU sparring fighters keep that angle to each other. As a
// success condition: |angle - angle0| <= within_deg.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <set>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "mgrl/core/data_paths.hpp"
#include "mgrl/learning/behavior_spec.hpp"
#include "mgrl/learning/real_bouts.hpp"
#include "term.hpp"

namespace mgrl::rewards {

namespace {

constexpr double kDegree = std::numbers::pi / 180;

// exp(-|angle - angle0| / sigma): angle0 written (angle_deg), or (prefer: stance)
// learned at bind from the real SNU sparring bouts: their facing angles (as prefer: bouts
// reads them) cut into `stances` equally large parts, angle0 the median of part `stance`. A
// scenario gives each stance its own behaviour (`stance: k`), and the world lets each fighter
// hold one at a time: the bout's facing then follows the real distribution part by part,
// which one preferred angle (the distribution's mode) cannot do.
class Facing final : public Term {
 public:
  explicit Facing(const Params& p)
      : angle_(p.number("angle_deg") * kDegree),
        sigma_(p.number("sigma_deg") * kDegree),
        stance_(p.choice("prefer") == "stance" ? static_cast<int>(p.integer("stance")) : -1),
        stances_(static_cast<int>(p.integer("stances"))) {
    if (stance_ >= stances_)
      throw TermError("stance", fmt::format("expected a stance below stances ({}), found {}", stances_, stance_));
  }

  void bind(const StateActionModel&) override {
    if (stance_ < 0) return;
    try {
      angle_ = facingStances(snuFacingDegrees(scenarioDataDirectory()), stances_)[static_cast<std::size_t>(stance_)] *
               kDegree;
    } catch (const Error& e) {
      throw TermError("prefer", fmt::format("stance: {}", e.what()));
    }
    bound_ = true;
  }

  double signal(const TermFrame& f) const override {
    if (!bound_) throw std::logic_error("facing term with a learned stance evaluated before it was bound");
    return std::exp(-std::abs(facingError(f.model, f.frame, f.target) - angle_) / sigma_);
  }

 private:
  double angle_, sigma_;  // rad
  int stance_, stances_;  // stance_ -1: angle_ as written
  bool bound_ = stance_ < 0;
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

// A preferred facing learned from capture, as a density over the signed angle from the
// avatar's facing to the target (per degree, smoothed with a circular Gaussian of `sigma`,
// normalised to 1 at its largest). The samples come from one of two sources:
// - prefer: hits: the signed angle from the avatar's facing to its own effective hitting
//   points (punches and kicks) at their frames, one sample per source frame and limb (an
//   action replaying a frame adds none): the stance its own strikes are thrown from;
// - prefer: bouts: the angle each fighter of the real SNU sparring bouts keeps to the
//   other at every frame, as `mgrl stats` measures it (unsigned, so each sample counts at
//   both signs): the real fighters' stance, circling and turning away included, which
//   shadow boxing, having no partner, does not record.
class FacingDensity final : public Term {
 public:
  explicit FacingDensity(const Params& p) : fromBouts_(p.choice("prefer") == "bouts"), sigma_(p.number("sigma_deg")) {}

  void bind(const StateActionModel& m) override {
    std::array<double, kBins> counts{};
    const std::size_t samples = fromBouts_ ? boutSamples(counts) : hitSamples(m, counts);
    if (samples == 0)
      throw TermError("prefer", fromBouts_ ? "expected frames in the SNU sparring bouts to learn the facing from "
                                             "(prefer: bouts), found none; use prefer: angle with angle_deg"
                                           : "expected effective punches or kicks in the capture to learn the facing "
                                             "from (prefer: hits), found none; use prefer: angle with angle_deg");
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
    if (!bound_) throw std::logic_error("facing term with a learned preference evaluated before it was bound");
    const double degrees = signedFacing(f.model, f.frame, f.target) / kDegree + 180;  // [0, 360]
    const double low = std::floor(degrees), w = degrees - low;
    const auto a = static_cast<std::size_t>(low) % kBins, b = (a + 1) % kBins;
    return (1 - w) * density_[a] + w * density_[b];
  }

 private:
  static constexpr int kBins = 360;  // one per degree, bin b at b - 180 degrees

  static void add(std::array<double, kBins>& counts, double degrees) {
    counts[static_cast<std::size_t>(std::lround(degrees + 180)) % kBins] += 1;
  }

  static std::size_t hitSamples(const StateActionModel& m, std::array<double, kBins>& counts) {
    std::set<std::pair<std::uint32_t, std::uint8_t>> seen;  // (source frame, limb)
    std::size_t samples = 0;
    auto addAll = [&](const std::vector<ActionHit>& list, std::uint8_t limb0) {
      for (const ActionHit& h : list) {
        const std::size_t k = m.actionFrameBegin[h.action] + h.offset - 1;
        if (!seen.emplace(m.actionFrames[k], static_cast<std::uint8_t>(limb0 + h.hand)).second) continue;
        add(counts, signedFacing(m, k, Eigen::Vector3d(h.x, h.y, h.z)) / kDegree);  // (-180, 180]
        ++samples;
      }
    };
    addAll(m.hits, 0);
    addAll(m.kicks, 2);
    return samples;
  }

  static std::size_t boutSamples(std::array<double, kBins>& counts) {
    const std::vector<double>* degrees = nullptr;
    try {
      degrees = &snuFacingDegrees(scenarioDataDirectory());
    } catch (const Error& e) {
      throw TermError("prefer", fmt::format("bouts: {}", e.what()));
    }
    for (const double d : *degrees) {
      add(counts, d);
      add(counts, -d);
    }
    return degrees->size();
  }

  bool fromBouts_;
  double sigma_;  // degrees
  std::array<double, kBins> density_{};
  bool bound_ = false;
};

}  // namespace

void registerFacing(Vocabulary& v) {
  const ParamSpec angle =
      ParamSpec::number("angle_deg", 0, 0, 180, "deg", "preferred angle (0: target straight ahead)");
  v.terms.add(
      {"facing",
       "exp(-|angle - angle0| / sigma), angle between the avatar's facing and the target's direction; or how "
       "often capture has that angle: (prefer: hits) the capture's own strikes, (prefer: bouts) the real SNU "
       "sparring bouts' fighters",
       {ParamSpec::choice("prefer", "angle", {"angle", "hits", "bouts", "stance"},
                          "angle: about angle_deg; hits: the capture's distribution of the signed angle from "
                          "the facing to its effective hitting points (its own stance); bouts: the distribution "
                          "of the angle the real SNU sparring bouts' fighters keep to each other (the data "
                          "folder's snu_martial_arts/motion/s_*.bvh, as mgrl stats measures it); both smoothed "
                          "by sigma_deg; stance: as angle, about the median of part `stance` of the bouts' angles "
                          "cut into `stances` equally likely parts"),
        ParamSpec::integer("stance", 0, 0, kMaxStances - 1, "",
                           "prefer: stance: which part of the real angles, from the smallest (0)"),
        ParamSpec::integer("stances", 3, 1, kMaxStances, "",
                           "prefer: stance: how many parts the real angles are cut into"),
        angle, ParamSpec::number("sigma_deg", 30, 0.1, 360, "deg", "angle scale of the exponential (of the smoothing)"),
        weightSpec()},
       [](const Params& p) -> std::unique_ptr<Term> {
         if (p.choice("prefer") == "hits" || p.choice("prefer") == "bouts") return std::make_unique<FacingDensity>(p);
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
