#pragma once
/// \file
/// Success criteria (scenarios/README.md, "success"): what counts as a behaviour having
/// done its job in a trial (`mgrl eval`, `mgrl compare`, the viewer's retraining), as
/// conditions on the body signals (mgrl/learning/signals.hpp) that hold together for
/// hold_s seconds:
///
///     success: {term: contact}                           # a strike lands (the paper's hit)
///     success: {term: distance, within: 0.2, hold_s: 1}  # |d - d0| <= 0.2 m for 1 s
///     success: {all: [{term: distance, within: 0.2}, {term: facing, within_deg: 30}], hold_s: 1}
///     success: {term: avoid, clear: 0.1, hold_s: 6}      # out of the opponent's reach for 6 s
///
/// A condition leaves out what the behaviour's reward already says: the body point, d0
/// and dims of its distance term, the effector and radius of its contact term, the
/// preferred angle of its facing term (the presets count as their terms: approach is a
/// distance from the centroid with d0 0, hit a contact of the fists within contact_radius).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "mgrl/core/config.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/target_state.hpp"
#include "mgrl/learning/signals.hpp"

namespace mgrl {

struct SuccessCondition {
  enum class Kind { Contact, Distance, Facing, Avoid };
  Kind kind = Kind::Contact;
  std::uint8_t effectors = kFists;  ///< contact; avoid: the opponent's strikes
  double radius = 0.15;             ///< contact (m)
  BodyPoint point;                        ///< distance; avoid: the point kept clear
  /// Where the point was written (distance), for bind()'s message; none if implied.
  std::optional<ConfigNode> pointNode;
  bool pointWritten = false;  ///< pointNode is the `point` key itself (else its condition)
  int dims = 2;                           ///< distance
  double d0 = 0, within = 0.2;            ///< distance: |d - d0| <= within (m)
  double angle = 0, withinAngle = 0.5235987755982988;  ///< facing: |error - angle| <= withinAngle (rad)
  double clear = 0.1;  ///< avoid: the point at least this far from every strike tip of the opponent (m)
  double bodyRadius = 0.2;  ///< avoid: each body's ground radius (m): the bodies at least `clear` apart too
  std::shared_ptr<const StrikeReach> reach;  ///< avoid, after bind()
  /// avoid: where the effector was written (its key, or the condition), for bind()'s message.
  std::optional<ConfigNode> effectorNode;
};

class SuccessCriterion {
 public:
  /// Reads a behaviour's `success:` block; what a condition leaves out comes from
  /// `reward`, the behaviour's reward block as JSON with defaults (Behavior::config
  /// ["reward"]). Throws ConfigError (file:line:col: key path) for a bad block.
  static SuccessCriterion read(const ConfigNode& block, const nlohmann::json& reward);
  /// The criterion a behaviour without `success:` has: its reward's contact landing (the
  /// paper's hit: an effective punch within contact_radius), if its reward has one.
  static std::optional<SuccessCriterion> implied(const nlohmann::json& reward);
  /// An effective punch of either fist within `radius` (what every trial counted before
  /// success criteria existed; the fallback for scenarios that declare none).
  static SuccessCriterion punch(double radius);

  /// Finds the joints the conditions name in `m` (see Reward::bind); throws ConfigError at
  /// the point's key, or mgrl::Error, naming the roles and joints the skeleton has.
  void bind(const StateActionModel& m);

  const std::vector<SuccessCondition>& conditions() const { return conditions_; }
  double holdSeconds() const { return hold_s_; }
  /// Whether every condition holds at offset t (1 = first frame) of action a, the target in
  /// state e then (in the decision's avatar frame; an opponent's facing is e.heading).
  bool holdsAt(const StateActionModel& m, std::size_t a, std::uint32_t t, const TargetState& e) const;
  /// {"all": [{"term": ..., ...}], "hold_s": s}.
  nlohmann::json toJson() const;
  /// "contact of the fists within 0.15 m", "pelvis within 0.2 m of 1.4 m and facing within 30 deg for 1 s".
  std::string describe() const;

  /// Follows one trial frame by frame across its actions.
  class Tracker {
   public:
    explicit Tracker(const SuccessCriterion& criterion, double frameTime);
    /// Plays action a from a decision in state e (a moving target followed frame by frame):
    /// the offset (1 = the action's first frame) at which the criterion is first met, 0 if
    /// it is not met in this action.
    std::uint32_t play(const StateActionModel& m, std::size_t a, const TargetState& e);
    const SuccessCriterion* criterion() const { return criterion_; }

   private:
    const SuccessCriterion* criterion_;
    std::size_t needed_ = 1, held_ = 0;
  };

 private:
  std::vector<SuccessCondition> conditions_;
  double hold_s_ = 0;
};

}  // namespace mgrl
