#pragma once
/// \file
/// Success criteria (scenarios/README.md, "success"): what counts as a behaviour having
/// done its job in a trial (`mgrl eval`, `mgrl compare`, the viewer's retraining), as
/// conditions that hold together for hold_s seconds. A condition is a reward term's measure
/// against a threshold: `term: NAME` names the term, the term's file registers the
/// condition beside it (rewards/distance.cpp, ...), and what the condition leaves out of
/// the term's own keys comes from the behaviour's reward term of that kind:
///
///     success: {term: contact}                           # a strike lands (the paper's hit)
///     success: {term: distance, within: 0.2, hold_s: 1}  # |d - d0| <= 0.2 m for 1 s
///     success: {all: [{term: distance, within: 0.2}, {term: facing, within_deg: 30}], hold_s: 1}
///     success: {term: avoid, clear: 0.1, hold_s: 6}      # out of the opponent's reach for 6 s
///
/// (the body point, d0 and dims of a distance term, the effector and radius of a contact
/// term, the preferred angle of a facing term; the presets count as their terms: approach
/// is a distance from the centroid with d0 0, hit a contact of the fists within
/// contact_radius, Reward::terms()).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "mgrl/core/config.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

class TrackedOpponent;

/// What a condition reads at offset t (1 = the first frame after the decision) of action
/// `action`.
struct ConditionFrame {
  const StateActionModel& model;
  std::size_t action;
  std::uint32_t t;
  std::size_t frame;          ///< the global action-frame index of t
  const TargetState& target;  ///< the target at t, in the decision's avatar frame (an opponent's facing: heading)
  /// A learned opponent: what it plays at t (`target` is then its head, as the
  /// reward terms see it). Null for other environments.
  const OpponentFrame* opponent = nullptr;
};

/// What an avoid condition keeps clear, for trials that play the opponent as an avatar
/// (Trials::runAgainstAvatar): a bound joint, the opponent's strikes, the margins.
struct Clearance {
  int joint = -1;
  std::uint8_t effectors = kFists;
  double clear = 0.1;       ///< m, from every strike tip and between the bodies
  double bodyRadius = 0.2;  ///< m, each body's ground radius
};

/// One condition: a term's measure at a frame against the condition's threshold.
class SuccessCondition {
 public:
  virtual ~SuccessCondition() = default;
  /// Finds what it reads in `m` (a joint, the opponent's strikes) before any holds().
  /// Throws KeyError naming its key at fault.
  virtual void bind(const StateActionModel&) {}
  virtual bool holds(const ConditionFrame& f) const = 0;
  /// {"term": NAME, its parameters...} for reports.
  virtual nlohmann::json toJson() const = 0;
  /// "the pelvis within 0.2 m of 1.4 m from the target".
  virtual std::string describe() const = 0;
  /// True if it holds at single frames only (a strike lands), so hold_s makes no sense.
  virtual bool instant() const { return false; }
  /// The avoid condition's clearance (it reads an opponent's strikes); none for others.
  virtual std::optional<Clearance> clearance() const { return std::nullopt; }
};

/// The condition kinds, one per reward term that has one: `term: NAME`, its parameters
/// (without `term` and `hold_s`) and Entry::inherited, the keys that default to the reward
/// term's values.
using ConditionRegistry = Registry<SuccessCondition>;

class SuccessCriterion {
 public:
  /// Reads a behaviour's `success:` block; what a condition leaves out comes from
  /// `rewardTerms`, the behaviour's reward as terms (Reward::terms(): a JSON list of
  /// {"term": NAME, parameters...}). Throws ConfigError (file:line:col: key path) for a bad block.
  static SuccessCriterion read(const ConfigNode& block, const nlohmann::json& rewardTerms,
                               const ConditionRegistry& kinds);
  /// The criterion a behaviour without `success:` has: its reward's contact landing (the
  /// paper's hit: an effective punch within contact_radius), if its reward has one.
  static std::optional<SuccessCriterion> implied(const nlohmann::json& rewardTerms, const ConditionRegistry& kinds);
  /// An effective punch of either fist within `radius` (what every trial counted before
  /// success criteria existed; the fallback for scenarios that declare none).
  static SuccessCriterion punch(double radius, const ConditionRegistry& kinds);

  /// Finds the joints the conditions name in `m` (see Reward::bind); throws ConfigError at
  /// the condition's key, or mgrl::Error, naming the roles and joints the skeleton has.
  void bind(const StateActionModel& m);

  std::size_t size() const { return conditions_.size(); }
  double holdSeconds() const { return hold_s_; }
  /// The first condition's clearance that has one (an avoid condition), else none.
  std::optional<Clearance> clearance() const;
  /// Whether every condition holds at offset t (1 = first frame) of action a, the target in
  /// state e then (in the decision's avatar frame; an opponent's facing is e.heading), a
  /// learned opponent playing `opponent` then.
  bool holdsAt(const StateActionModel& m, std::size_t a, std::uint32_t t, const TargetState& e,
               const OpponentFrame* opponent = nullptr) const;
  /// {"all": [{"term": ..., ...}], "hold_s": s, "text": describe()}.
  nlohmann::json toJson() const;
  /// "an effective strike of the fists within 0.15 m", "the pelvis within 0.2 m of 1.4 m
  /// from the target and facing within 30 deg of 0 deg off the target for 1 s".
  std::string describe() const;

  /// Follows one trial frame by frame across its actions.
  class Tracker {
   public:
    explicit Tracker(const SuccessCriterion& criterion, double frameTime);
    /// Plays action a from a decision in state e (a moving target followed frame by frame;
    /// a learned `opponent` as its track() has it, so that a condition sees the head and
    /// the strikes the reward terms see): the offset (1 = the action's first frame) at
    /// which the criterion is first met, 0 if it is not met in this action.
    std::uint32_t play(const StateActionModel& m, std::size_t a, const TargetState& e,
                       const TrackedOpponent* opponent = nullptr);
    const SuccessCriterion* criterion() const { return criterion_; }

   private:
    const SuccessCriterion* criterion_;
    std::size_t needed_ = 1, held_ = 0;
    int head_ = -2;  ///< the model's head joint for a learned opponent's target; -2 not yet looked up
  };

 private:
  struct Read {
    /// Shared: criteria are copied per trial set and avatar once bound (binding a copy binds
    /// every copy).
    std::shared_ptr<SuccessCondition> condition;
    std::string term;                ///< its kind
    std::optional<ConfigNode> node;  ///< where it was written, for bind()'s messages
  };
  std::vector<Read> conditions_;
  double hold_s_ = 0;
};

}  // namespace mgrl
