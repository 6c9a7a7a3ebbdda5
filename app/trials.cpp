// The trials `mgrl eval` reports and `mgrl compare` evaluates snapshots with (trials.hpp).
#include "trials.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/runtime/controller.hpp"

namespace mgrl::app {

using json = nlohmann::json;

Trials::Trials(const StateActionModel& model, const std::vector<Behavior>& behaviors, double targetHeight,
               const std::string& source)
    : model_(model), behaviors_(behaviors) {
  // The approach region: the first always-active behaviour's grid, sampled uniformly by area.
  const auto region = std::find_if(behaviors.begin(), behaviors.end(),
                                   [](const Behavior& b) { return b.activation == Activation::Always; });
  region_ = (region != behaviors.end() ? region : behaviors.begin())->discretizer.get();
  for (const GridAxis& axis : region_->axes())
    if (axis.name == "distance") reach_ = axis.vertices.back();
  if (!(reach_ > 0))
    throw Error(fmt::format("{}: expected a behaviour whose grid has a distance axis to place targets in, found none",
                            source));
  // The target's height: given, else that of the effective hitting points' centroid (a
  // target at punching height, as the user's target in the paper's demo).
  targetHeight_ = std::isnan(targetHeight) ? model.centroid[1] : targetHeight;
  // Targets are drawn by rejection: refuse a region no target at this height falls in
  // (a 3-D grid whose heights miss it) instead of searching forever.
  Rng probe(1);
  std::size_t inside = 0;
  for (int i = 0; i < 100000 && inside == 0; ++i)
    inside += region_->inside({(2 * probe.uniform() - 1) * reach_, targetHeight_, (2 * probe.uniform() - 1) * reach_});
  if (inside == 0)
    throw Error(fmt::format("{}: expected targets at height {:.2f} m to fall inside the grid of the behaviour that "
                            "places them, found none in 100000 draws (set --target-height or world.target_height "
                            "inside its heights)",
                            source, targetHeight_));
  // Success: what the behaviours declare, else what the first contact reward implies, else
  // a punch (what trials counted before success criteria). Returns are discounted with the
  // first behaviour's gamma.
  std::tie(criteria_, criteriaFrom_) = trialCriteria(behaviors);
  environment_ = behaviors.front().environment.get();
  gamma_ = behaviors.front().reward->gamma();
}

std::pair<std::vector<SuccessCriterion>, std::string> trialCriteria(const std::vector<Behavior>& behaviors) {
  std::vector<SuccessCriterion> criteria;
  for (const Behavior& b : behaviors)
    if (b.successDeclared && b.success) criteria.push_back(*b.success);
  if (!criteria.empty()) return {std::move(criteria), "declared"};
  for (const Behavior& b : behaviors)
    if (b.success) return {{*b.success}, "implied"};
  return {{SuccessCriterion::punch(0.15)}, "fallback"};
}

// A target uniform by area in the approach region's square of side 2 reach, at the target
// height, rejected until the region holds it. The constructor has checked that some do.
// A moving target's motion is drawn after its position (a static target draws nothing, so
// its trials are those of before moving targets).
TargetState Trials::placeTarget(Rng& starts) const {
  for (;;) {
    const Eigen::Vector3d e((2 * starts.uniform() - 1) * reach_, targetHeight_, (2 * starts.uniform() - 1) * reach_);
    if (region_->inside(e)) return environment_->draw(e, starts);
  }
}

TrialStats Trials::run(const ChooseAction& choose, std::size_t count, double seconds, std::uint64_t seed,
                       std::vector<std::pair<std::uint32_t, TargetState>>* decisions) const {
  const StateActionModel& model = model_;
  const EnvironmentModel& environment = *environment_;
  Rng starts(seed), choices(seed ^ 0x5eed5eed5eedULL);
  TrialStats stats;
  stats.trials = count;
  const double limit = seconds / model.frameTime;
  const bool opponent = environment.type() == "opponent";
  for (std::size_t trial = 0; trial < count; ++trial) {
    auto s = static_cast<std::uint32_t>(starts.below(model.stateCount()));
    TargetState e = placeTarget(starts);
    double elapsed = 0, discount = 1, trialReturn = 0;
    bool hit = false;
    std::vector<SuccessCriterion::Tracker> trackers;
    for (const SuccessCriterion& c : criteria_) trackers.emplace_back(c, model.frameTime);
    while (elapsed < limit && !hit) {
      std::size_t a;
      if (choose) {
        if (decisions) decisions->emplace_back(s, e);
        a = choose(s, e);
      } else {
        a = model.stateActionBegin[s] + choices.below(model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
      }
      ++stats.decisions;
      double reward = 0;
      for (const Behavior& b : behaviors_) {
        if (b.activation == Activation::TargetInside && !b.discretizer->inside(e)) continue;
        reward += b.weight * b.reward->evaluate(model, a, e);
      }
      trialReturn += discount * reward;
      std::uint32_t first = 0;  // the earliest offset any criterion is met at
      for (SuccessCriterion::Tracker& tracker : trackers)
        if (const std::uint32_t t = tracker.play(model, a, e); t > 0 && (first == 0 || t < first)) first = t;
      if (first > 0) {
        hit = true;
        stats.hitTimes.push_back((elapsed + first) * model.frameTime);
      }
      if (opponent) {
        const std::size_t begin = model.actionFrameBegin[a], end = begin + model.actionLength(a);
        for (std::size_t f = begin; f < end; ++f) {
          stats.opponentGaps.push_back(static_cast<float>(
              std::hypot(model.frameRoot[3 * f] - e.position.x(), model.frameRoot[3 * f + 1] - e.position.z())));
          stats.opponentFacing.push_back(static_cast<float>(facingError(model, f, e.position) * 180 / M_PI));
        }
      }
      const auto frames = static_cast<double>(model.actionLength(a));
      discount *= std::pow(gamma_, frames);
      elapsed += frames;
      e = environment.next(model, a, e);
      s = model.actionTo[a];
    }
    stats.successes += hit;
    stats.returns += trialReturn;
  }
  return stats;
}

json Trials::successJson() const {
  json criteria = json::array();
  std::vector<std::string> texts;
  for (const SuccessCriterion& c : criteria_) {
    criteria.push_back(c.toJson());
    texts.push_back(c.describe());
  }
  return {{"criteria", criteria}, {"from", criteriaFrom_}, {"text", fmt::format("{}", fmt::join(texts, ", or "))}};
}

json Trials::summary(TrialStats stats) {
  std::sort(stats.hitTimes.begin(), stats.hitTimes.end());
  const std::size_t n = stats.hitTimes.size();
  double mean = 0;
  for (double t : stats.hitTimes) mean += t;
  json times = nullptr, median = nullptr;
  if (n > 0) {
    times = mean / static_cast<double>(n);
    median = n % 2 ? stats.hitTimes[n / 2] : (stats.hitTimes[n / 2 - 1] + stats.hitTimes[n / 2]) / 2;
  }
  const auto trials = static_cast<double>(std::max<std::size_t>(1, stats.trials));
  json result{{"success_rate", static_cast<double>(stats.successes) / trials},
              {"successes", stats.successes},
              {"mean_time_to_hit_s", times},
              {"median_time_to_hit_s", median},
              {"mean_return", stats.returns / trials},
              {"decisions", stats.decisions}};
  if (!stats.opponentGaps.empty()) {
    std::vector<float>& gaps = stats.opponentGaps;
    std::sort(gaps.begin(), gaps.end());
    result["opponent_gap_m"] = {{"median", gaps[gaps.size() / 2]}, {"p5", gaps[gaps.size() / 20]}, {"min", gaps.front()}};
    std::vector<float>& facing = stats.opponentFacing;
    std::sort(facing.begin(), facing.end());
    result["opponent_facing_deg"] = {{"median", facing[facing.size() / 2]}, {"p95", facing[facing.size() * 19 / 20]}};
  }
  return result;
}

}  // namespace mgrl::app
