// The trials `mgrl eval` reports and `mgrl compare` evaluates snapshots with (trials.hpp).
#include "mgrl/session/trials.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/runtime/controller.hpp"

namespace mgrl {

using json = nlohmann::json;

Trials::Trials(const StateActionModel& model, const std::vector<Behavior>& behaviors, const Task& task,
               double targetHeight, const std::string& source, const ConditionRegistry& conditions)
    : model_(model), behaviors_(behaviors) {
  // The approach region: the first always-active behaviour's grid, sampled uniformly by area.
  const auto region = std::find_if(behaviors.begin(), behaviors.end(),
                                   [](const Behavior& b) { return b.activation == Activation::Always; });
  region_ = (region != behaviors.end() ? region : behaviors.begin())->discretizer.get();
  stances_ = stanceCount(behaviors);
  if (const GridAxis* distance = region_->axis(AxisRole::Distance)) reach_ = distance->vertices.back();
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
    inside += insideRegion({(2 * probe.uniform() - 1) * reach_, targetHeight_, (2 * probe.uniform() - 1) * reach_});
  if (inside == 0)
    throw Error(fmt::format("{}: expected targets at height {:.2f} m to fall inside the grid of the behaviour that "
                            "places them, found none in 100000 draws (set --target-height or world.target_height "
                            "inside its heights)",
                            source, targetHeight_));
  // Success: what the behaviours declare, else what the first contact reward implies, else
  // a punch (what trials counted before success criteria). Returns are discounted with the
  // task's gamma.
  std::tie(criteria_, criteriaFrom_) = trialCriteria(behaviors, conditions);
  environment_ = task.environment;
  opponent_ = task.opponent;
  targetMotion_ = task.targetMotion;
  trackedOpponent_ = task.trackedOpponent;
  scriptedOpponent_ = task.scriptedOpponent;
  gamma_ = task.gamma;
}

std::pair<std::vector<SuccessCriterion>, std::string> trialCriteria(const std::vector<Behavior>& behaviors,
                                                                    const ConditionRegistry& conditions) {
  std::vector<SuccessCriterion> criteria;
  // One of each: a scenario's stances declare the same criterion once a stance.
  for (const Behavior& b : behaviors)
    if (b.successDeclared && b.success &&
        std::none_of(criteria.begin(), criteria.end(),
                     [&](const SuccessCriterion& c) { return c.toJson() == b.success->toJson(); }))
      criteria.push_back(*b.success);
  if (!criteria.empty()) return {std::move(criteria), "declared"};
  for (const Behavior& b : behaviors)
    if (b.success) return {{*b.success}, "implied"};
  return {{SuccessCriterion::punch(0.15, conditions)}, "fallback"};
}

// A target uniform by area in the approach region's square of side 2 reach, at the target
// height, rejected until the region holds it. The constructor has checked that some do.
// A moving target's motion is drawn after its position (a static target draws nothing, so
// its trials are those of before moving targets).
// Whether a target placed at `position` falls in the placing grid: on a grid with a learned
// opponent's layers, in the first layer (every layer has the same positions).
bool Trials::insideRegion(const Eigen::Vector3d& position) const {
  TargetState e(position);
  if (region_->hasOpponentLayers()) e.opponent = 0;
  return region_->inside(e);
}

TargetState Trials::placeTarget(Rng& starts) const {
  for (;;) {
    const Eigen::Vector3d e((2 * starts.uniform() - 1) * reach_, targetHeight_, (2 * starts.uniform() - 1) * reach_);
    if (insideRegion(e)) return environment_->draw(e, starts);
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
  if (targetMotion_) stats.turnRates = targetMotion_->turnRates;
  stats.turnTrials.assign(stats.turnRates.size(), 0);
  stats.turnSuccesses.assign(stats.turnRates.size(), 0);
  for (std::size_t trial = 0; trial < count; ++trial) {
    auto s = static_cast<std::uint32_t>(starts.below(model.stateCount()));
    TargetState e = placeTarget(starts);
    // Stances in turn, trial by trial: each held through its trial.
    e.stance = stanceOf(trial);
    const auto turn = static_cast<std::size_t>(std::find(stats.turnRates.begin(), stats.turnRates.end(), e.turnRate) -
                                               stats.turnRates.begin());
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
        if (!stanceActive(b.stance, e.stance)) continue;
        if (b.activation == Activation::TargetInside && !b.discretizer->inside(e)) continue;
        reward += b.weight * b.reward->evaluate(model, a, e);
      }
      trialReturn += discount * reward;
      std::uint32_t first = 0;  // the earliest offset any criterion is met at
      for (SuccessCriterion::Tracker& tracker : trackers)
        if (const std::uint32_t t = tracker.play(model, a, e, trackedOpponent_); t > 0 && (first == 0 || t < first))
          first = t;
      if (first > 0) {
        hit = true;
        stats.hitTimes.push_back((elapsed + first) * model.frameTime);
      }
      if (opponent_) {
        const std::size_t begin = model.actionFrameBegin[a], end = begin + model.actionLength(a);
        for (std::size_t f = begin; f < end; ++f) {
          stats.opponentGaps.push_back(static_cast<float>(bodyDistance(model, f, BodyPoint::pelvis(), 2, e.position)));
          stats.opponentFacing.push_back(static_cast<float>(facingError(model, f, e.position) * 180 / M_PI));
        }
      }
      const auto frames = static_cast<double>(model.actionLength(a));
      discount *= std::pow(gamma_, frames);
      elapsed += frames;
      e = nextHoldingStance(environment, model, a, e);
      s = model.actionTo[a];
    }
    stats.successes += hit;
    stats.returns += trialReturn;
    if (turn < stats.turnRates.size()) {
      ++stats.turnTrials[turn];
      stats.turnSuccesses[turn] += hit;
    }
  }
  return stats;
}

std::pair<std::optional<Clearance>, double> Trials::avoidCondition() const {
  for (const SuccessCriterion& c : criteria_)
    if (std::optional<Clearance> found = c.clearance()) return {found, c.holdSeconds()};
  return {std::nullopt, 0};
}

bool Trials::hasAvatarOpponent() const { return scriptedOpponent_ && avoidCondition().first.has_value(); }

TrialStats Trials::runAgainstAvatar(const ChooseAction& choose, std::size_t count, double seconds,
                                    std::uint64_t seed) const {
  const StateActionModel& model = model_;
  const ScriptedOpponent* opponentModel = scriptedOpponent_;
  if (!opponentModel)
    throw Error(fmt::format("trials against an avatar: expected an opponent environment, found {}", environment_->type()));
  // Not a structured binding: the lambdas below capture it (clang before 16 cannot).
  const std::pair<std::optional<Clearance>, double> found = avoidCondition();
  const std::optional<Clearance> avoid = found.first;
  const double hold = found.second;
  if (!avoid) throw Error("trials against an avatar: expected a success criterion with an avoid condition, found none");
  const auto needed = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(hold / model.frameTime)));
  const auto limit = static_cast<std::size_t>(seconds / model.frameTime);
  Rng starts(seed), choices(seed ^ 0x5eed5eed5eedULL), opponentRng(seed ^ 0x0bb0bb0bb0ULL);
  TrialStats stats;
  stats.trials = count;

  // One avatar on the graph: where its current action started (world), the action, and
  // how many of its frames have played.
  struct Player {
    std::uint32_t state = 0, action = 0, played = 0, length = 0;
    GroundMotion decision;
  };
  auto rootAt = [&](const Player& p) {  // the root's world pose at the frame just played
    if (p.played == 0) return p.decision;
    const double* r = &model.frameRoot[3 * (model.actionFrameBegin[p.action] + p.played - 1)];
    return compose(p.decision, {r[0], r[1], r[2]});
  };
  auto finish = [&](Player& p) {  // the pose after the whole action: the next decision's frame
    p.decision = compose(p.decision, model.displacement(p.action));
    p.state = model.actionTo[p.action];
  };
  auto start = [&](Player& p, std::size_t a) {
    p.action = static_cast<std::uint32_t>(a);
    p.played = 0;
    p.length = static_cast<std::uint32_t>(model.actionLength(a));
  };
  // The opponent's choice, greedy over its out-actions: a punch of the action landing near
  // the avatar's point where it is now (the paper's hit, sec. 6.4) first, then ending
  // nearest stop_distance from the avatar (or its own start, standing) and facing it; the
  // capture is all it can play. The world's scripted opponent (PursueController) plays the
  // same rule and weights.
  auto opponentChoice = [&](const Player& o, const Eigen::Vector3d& avatar, const Eigen::Vector3d& target,
                            const Eigen::Vector3d& home) {
    const std::size_t first = model.stateActionBegin[o.state], last = model.stateActionBegin[o.state + 1];
    std::size_t best = first;
    double bestCost = 1e300;
    const Eigen::Vector3d aim = inverseTransformPoint(o.decision, target);
    for (std::size_t a = first; a < last; ++a) {
      const GroundMotion end = compose(o.decision, model.displacement(a));
      const Eigen::Vector3d q = inverseTransformPoint(end, avatar);
      const double facing = std::abs(std::atan2(q.x(), q.z()));
      const double place = !opponentModel->stand ? std::abs(std::hypot(q.x(), q.z()) - opponentModel->stopDistance)
                                                 : std::hypot(end.dx - home.x(), end.dz - home.z());
      const double punch = PursueController::punchScore(model.hitsOf(a), aim);
      if (const double cost = place + PursueController::kTurnCost * facing - PursueController::kPunchWeight * punch;
          cost < bestCost) {
        bestCost = cost;
        best = a;
      }
    }
    return best;
  };

  for (std::size_t trial = 0; trial < count; ++trial) {
    Player avatar, opponent;
    avatar.state = static_cast<std::uint32_t>(starts.below(model.stateCount()));
    const TargetState placed = placeTarget(starts);
    opponent.state = static_cast<std::uint32_t>(opponentRng.below(model.stateCount()));
    opponent.decision = {placed.position.x(), placed.position.z(), placed.heading};
    const Eigen::Vector3d home(placed.position.x(), 0, placed.position.z());
    std::size_t held = 0, frame = 0;
    bool first = true, succeeded = false;
    for (; frame < limit; ++frame) {
      if (first || avatar.played == avatar.length) {
        if (!first) finish(avatar);
        const GroundMotion o = rootAt(opponent);
        TargetState e(inverseTransformPoint(avatar.decision, {o.dx, targetHeight_, o.dz}), 0.0,
                      std::remainder(o.dyaw - avatar.decision.dyaw, 2 * M_PI));
        e.stance = stanceOf(trial);
        const std::size_t begin = model.stateActionBegin[avatar.state], end = model.stateActionBegin[avatar.state + 1];
        start(avatar, choose ? choose(avatar.state, e) : begin + choices.below(end - begin));
        ++stats.decisions;
      }
      if (first || opponent.played == opponent.length) {
        if (!first) finish(opponent);
        const GroundMotion a = rootAt(avatar);
        const std::size_t f = model.actionFrameBegin[avatar.action] + std::max<std::uint32_t>(avatar.played, 1) - 1;
        const Eigen::Vector3d target = transformPoint(avatar.decision, jointAt(model, f, avoid->joint));
        start(opponent, opponentChoice(opponent, {a.dx, 0, a.dz}, target, home));
      }
      first = false;
      ++avatar.played;
      ++opponent.played;
      const std::size_t f = model.actionFrameBegin[avatar.action] + avatar.played - 1;
      const GroundMotion me = rootAt(avatar), them = rootAt(opponent);
      const Eigen::Vector3d point = transformPoint(avatar.decision, jointAt(model, f, avoid->joint));
      const double gap = std::hypot(me.dx - them.dx, me.dz - them.dz);  // pelvis to pelvis, on the ground
      bool reached = gap - 2 * avoid->bodyRadius < avoid->clear;
      auto strikes = [&](std::span<const ActionHit> list, std::uint8_t leftBit) {
        for (const ActionHit& h : list) {
          if (h.offset != opponent.played || !(avoid->effectors & (leftBit << h.hand))) continue;
          const Eigen::Vector3d tip = transformPoint(opponent.decision, Eigen::Vector3d(h.x, h.y, h.z));
          if ((tip - point).norm() < avoid->clear) {
            reached = true;
            ++stats.strikesReached;
          }
        }
      };
      if (avoid->effectors & kFists) strikes(model.hitsOf(opponent.action), kLeftFist);
      if ((avoid->effectors & kFeet) && !model.actionKickBegin.empty()) strikes(model.kicksOf(opponent.action), kLeftFoot);
      stats.opponentGaps.push_back(static_cast<float>(gap));
      const Eigen::Vector3d toward = inverseTransformPoint(me, {them.dx, 0, them.dz});
      stats.opponentFacing.push_back(static_cast<float>(std::abs(std::atan2(toward.x(), toward.z())) * 180 / M_PI));
      stats.framesOverlapping += gap < 2 * avoid->bodyRadius;
      // The whole trial plays on after a success: strikes and overlaps are counted over all of it.
      held = reached ? 0 : held + 1;
      if (held == needed && !succeeded) {
        succeeded = true;
        ++stats.successes;
        stats.hitTimes.push_back(static_cast<double>(frame + 1) * model.frameTime);
      }
    }
    stats.secondsPlayed += static_cast<double>(frame) * model.frameTime;
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
  if (stats.secondsPlayed > 0) {
    result["strikes_reached_per_minute"] = 60 * static_cast<double>(stats.strikesReached) / stats.secondsPlayed;
    result["bodies_overlapping"] = static_cast<double>(stats.framesOverlapping) /
                                   static_cast<double>(std::max<std::size_t>(1, stats.opponentGaps.size()));
  }
  if (!stats.turnRates.empty()) {
    json turns = json::array();
    for (std::size_t k = 0; k < stats.turnRates.size(); ++k)
      turns.push_back({{"turn_deg_s", stats.turnRates[k] * 180 / M_PI},
                       {"trials", stats.turnTrials[k]},
                       {"successes", stats.turnSuccesses[k]},
                       {"success_rate", static_cast<double>(stats.turnSuccesses[k]) /
                                            static_cast<double>(std::max<std::size_t>(1, stats.turnTrials[k]))}});
    result["by_turn_rate"] = std::move(turns);
  }
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

}  // namespace mgrl
