#pragma once
/// \file
/// The evaluation trials of `mgrl eval` and `mgrl compare` (DESIGN.md sec. 5): from random
/// starts (a state of the graph, a target on the floor of the first always-active
/// behaviour's grid, at the target height, moving as the first behaviour's environment model
/// draws it: static, or a moving_target's speed and direction) a controller acts until the scenario's success
/// criterion is met (mgrl/learning/success.hpp), or the trial's motion runs out. The
/// criterion: the behaviours' declared `success:` (any of them met), else the first one
/// implied by a reward's contact term (the paper's hit: an effective punch within
/// contact_radius), else an effective punch within 0.15 m.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "mgrl/core/random.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/session/task.hpp"

namespace mgrl {

/// The criteria a trial succeeds by (any of them): the behaviours' declared `success:`,
/// else the first one a reward's contact term implies, else an effective punch within
/// 0.15 m; and where they came from: "declared", "implied" or "fallback". The viewer
/// counts its avatars' successes by the same criteria.
/// `conditions`: where the fallback punch comes from (Plugins::conditions).
std::pair<std::vector<SuccessCriterion>, std::string> trialCriteria(const std::vector<Behavior>& behaviors,
                                                                    const ConditionRegistry& conditions);

struct TrialStats {
  std::size_t trials = 0, successes = 0, decisions = 0;
  std::vector<double> hitTimes;  ///< seconds to success, one per success
  double returns = 0;            ///< sum over trials of the discounted weighted reward
  /// An opponent's trials: the ground distance from the avatar's pelvis to the
  /// opponent's ground point at every frame played (the spacing a viewer would see).
  std::vector<float> opponentGaps;
  /// ... and the angle (deg) between the avatar's facing and the direction to the opponent.
  std::vector<float> opponentFacing;
  /// runAgainstAvatar(): the opponent's effective strikes that reached the avatar's point
  /// (within the avoid condition's `clear`), the frames the two bodies overlapped (pelvis
  /// gap under two body radii), and the seconds played.
  std::size_t strikesReached = 0, framesOverlapping = 0;
  double secondsPlayed = 0;
  /// With a turning target: per turn rate the environment model draws (rad/s,
  /// ascending), the trials that drew it and how many succeeded; empty otherwise.
  std::vector<double> turnRates;
  std::vector<std::size_t> turnTrials, turnSuccesses;
};

/// Picks an action of state s (a global action index) for the environment state e (avatar frame).
using ChooseAction = std::function<std::size_t(std::uint32_t s, const TargetState& e)>;

class Trials {
 public:
  /// `targetHeight` NaN: the effective hitting points' centroid height. The target moves as
  /// `task`'s environment model moves it, returns are discounted with its gamma. Throws
  /// mgrl::Error naming `source` (the scenario) if no behaviour's grid has a distance axis
  /// to place targets in. Keeps references to `model`, `behaviors` and what `task` points to.
  /// `conditions` gives the fallback success criterion (trialCriteria()).
  Trials(const StateActionModel& model, const std::vector<Behavior>& behaviors, const Task& task, double targetHeight,
         const std::string& source, const ConditionRegistry& conditions);

  /// Runs `count` trials of `seconds` of motion each from the starts drawn with `seed`:
  /// the first k trials of any count start alike. `choose` null: uniformly random actions.
  /// `decisions`, if given, receives every (state, target) a decision was asked for.
  TrialStats run(const ChooseAction& choose, std::size_t count, double seconds, std::uint64_t seed,
                 std::vector<std::pair<std::uint32_t, TargetState>>* decisions = nullptr) const;

  /// True if runAgainstAvatar() can run: an opponent environment and an avoid condition.
  bool hasAvatarOpponent() const;
  /// An opponent scenario's trials against another avatar of the graph instead of the
  /// environment model's opponent: the opponent plays the capture itself, action
  /// by action, greedily: an action whose punch lands near the avatar's point first, then
  /// one ending stop_distance from the avatar and facing it (`policy: pursue`; `stand`:
  /// near its start), and throws its effective strikes at the frames they happen. A trial
  /// succeeds when, for the avoid condition's hold_s, no strike tip came within `clear` of
  /// the avatar's point and the bodies stayed `clear` apart; every trial plays all its
  /// seconds, so strikes and overlaps are counted over the same time for any controller.
  /// Throws mgrl::Error if the scenario's environment is not an opponent or no criterion
  /// has an avoid condition.
  TrialStats runAgainstAvatar(const ChooseAction& choose, std::size_t count, double seconds, std::uint64_t seed) const;

  /// {"success_rate", "successes", "mean_time_to_hit_s" (seconds to success; null without
  ///  one), "median_time_to_hit_s", "mean_return", "decisions"}, and for an opponent
  ///  "opponent_gap_m": {"median", "p5", "min"} of TrialStats::opponentGaps and
  ///  "opponent_facing_deg": {"median", "p95"} of TrialStats::opponentFacing.
  static nlohmann::json summary(TrialStats stats);

  double targetHeight() const { return targetHeight_; }
  /// The criteria a trial succeeds by (any of them), and where they came from.
  const std::vector<SuccessCriterion>& criteria() const { return criteria_; }
  /// {"criteria": [SuccessCriterion::toJson()...], "from": "declared"|"implied"|"fallback", "text": "..."}.
  nlohmann::json successJson() const;

 private:
  TargetState placeTarget(Rng& starts) const;
  /// The first avoid condition's clearance and its criterion's hold_s; none if no criterion has one.
  std::pair<std::optional<Clearance>, double> avoidCondition() const;
  /// The first behaviour's environment model: how trial targets move (all behaviours see
  /// the same target), and the task's capabilities of it.
  const EnvironmentModel* environment_ = nullptr;
  bool opponent_ = false;  ///< Task::opponent: it faces the avatar
  const TargetMotion* targetMotion_ = nullptr;
  const TrackedOpponent* trackedOpponent_ = nullptr;
  const ScriptedOpponent* scriptedOpponent_ = nullptr;
  const StateActionModel& model_;
  const std::vector<Behavior>& behaviors_;
  const Discretizer* region_ = nullptr;
  bool insideRegion(const Eigen::Vector3d& position) const;
  double reach_ = 0, targetHeight_ = 0, gamma_ = 0.97;
  int stances_ = 0;  ///< behaviours' stances: trial i holds stance i mod stances_
  /// Trial i's stance: i mod stances_, -1 without stances.
  std::int32_t stanceOf(std::size_t trial) const {
    return stances_ > 0 ? static_cast<std::int32_t>(trial % static_cast<std::size_t>(stances_)) : -1;
  }
  std::vector<SuccessCriterion> criteria_;
  std::string criteriaFrom_;
};

}  // namespace mgrl
