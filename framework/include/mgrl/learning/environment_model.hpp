#pragma once
/// \file
/// The EnvironmentModel seam (DESIGN.md sec. 4; paper sec. 4.1, 6.4): how the environment
/// state (the target, or an opponent, in the avatar frame of the decision) changes over one
/// graph action, and the two models every build has, `static_target` (the paper's) and
/// `moving_target`. The other models are plug-ins in environments/.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/random.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

/// A scripted opponent fighter, as the runtime world plays it with graph actions: the
/// second avatar of a pair pursues the first to `stopDistance`, or takes the actions that
/// move it least (`stand`).
struct ScriptedOpponent {
  bool stand = false;
  double stopDistance = 0;
};

class QTable;
class Discretizer;

/// The EnvironmentModel seam: the environment state in the avatar frame at the end of an
/// action, given the state at the decision.
class EnvironmentModel {
 public:
  virtual ~EnvironmentModel() = default;
  virtual std::string type() const = 0;
  virtual TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const = 0;
  /// True if next() is exactly inverseTransformPoint(model.displacement(action), e.position)
  /// with speed 0, so learners may apply it from precomputed sines and cosines.
  virtual bool rigid() const { return false; }
  /// True if next() keeps the speed bit for bit, as a grid with speed layers requires.
  virtual bool keepsSpeed() const { return false; }
  /// The state of an evaluation trial's target placed at `position` (eval, compare): the
  /// position alone for a static target; a moving one draws its motion from `rng`.
  virtual TargetState draw(const Eigen::Vector3d& position, Rng&) const { return position; }
  /// The most a draw() may ask of a grid's layer axis (its top speed), m/s.
  virtual double maxSpeed() const { return 0; }
  /// The turn rates (rad/s, ascending) a draw() picks one of per episode and next() keeps bit
  /// for bit (issue 46's turning targets): the behaviour's grid gets one layer per rate
  /// (Discretizer::setTurnLayers). Empty for a model whose targets do not turn.
  virtual std::vector<double> turnRates() const { return {}; }
  /// True if the state's heading is which way the target faces (an `opponent`), not where
  /// it moves: its grid must hold a heading, the world supplies it (a sparring partner's
  /// facing, a dragged target's toward the avatar), and trials report the spacing to it.
  virtual bool faces() const { return false; }

  // A learned opponent (issue 43): an avatar of the same graph playing a policy table, whose
  // discrete state (graph state and phase) is TargetState::opponent, one grid layer each.

  /// Prepares the model for `model` before any next(); throws mgrl::Error.
  virtual void bind(const StateActionModel&) {}
  /// The number of discrete opponent states (layers the grid gets), 0 for none.
  virtual std::size_t opponentStates() const { return 0; }
  /// The phase buckets per graph state of those (opponentStateIndex()), 0 for none: what the
  /// runtime world needs to tell a controller what a sparring partner is doing.
  virtual int opponentPhases() const { return 0; }
  /// What the opponent does at frames 1..L of action a from e (out[t - 1] for frame t, L
  /// entries); false (out untouched) for a model without a learned opponent.
  virtual bool track(const StateActionModel&, std::size_t /*action*/, const TargetState&,
                     std::vector<OpponentFrame>& /*out*/) const {
    return false;
  }
  /// Makes the opponent play `table` on `grid` (the same grid, opponent layers included, as
  /// the behaviour's own: self-play; it must outlive this model); a null table: its scripted
  /// policy. `key` names the
  /// table for the behaviour's key. Throws mgrl::Error for a model without one, or a table
  /// of another shape.
  virtual void playPolicy(const Discretizer* grid, std::shared_ptr<const QTable> table, const std::string& key);
  /// Self-play rounds `mgrl train` runs (round k's opponent plays round k - 1's table).
  virtual int rounds() const { return 1; }
  /// True when round k's opponent plays the mean of rounds 1..k - 1's tables instead of
  /// round k - 1's alone (a stand-in for fictitious self-play, issue 43).
  virtual bool roundsAgainstAverage() const { return false; }
  /// What the opponent plays, for messages and records: "" without a learned opponent.
  virtual std::string policyKey() const { return ""; }
  /// The policy bundle directory the scenario asks the opponent to play, "" for none (a
  /// scripted opponent, or none at all); buildBehavior() loads it and calls playPolicy().
  virtual std::string policySource() const { return ""; }
  /// The scripted fighter this model stands for (an `opponent`), so that the world and
  /// trials against an avatar can play it with graph actions; empty for any other model.
  virtual std::optional<ScriptedOpponent> scriptedOpponent() const { return std::nullopt; }
};

/// `environment.next(model, action, e)` with e's stance held (TargetState::stance): what
/// trials and the online search step a stance-holding target with.
inline TargetState nextHoldingStance(const EnvironmentModel& environment, const StateActionModel& model,
                                     std::size_t action, const TargetState& e) {
  TargetState after = environment.next(model, action, e);
  after.stance = e.stance;
  return after;
}

using EnvironmentRegistry = Registry<EnvironmentModel>;

/// `static_target`: the target stays put in the world, so its new avatar-frame position is
/// the old one seen from the action's end, exactly (DESIGN.md sec. 3): the inverse of the
/// action's root displacement applied to e. Height is unchanged.
class StaticTarget final : public EnvironmentModel {
 public:
  std::string type() const override { return "static_target"; }
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;
  bool rigid() const override { return true; }
};

/// `moving_target`: the target moves on the ground at a constant speed for the episode, in
/// a straight line or, at a turn rate, round a circle (what TargetState::at() predicts);
/// after an action of T seconds it is at TargetState::at(T) seen from the action's end, its
/// heading turned by w T and back by the avatar's yaw. The speed and the turn rate are
/// kept bit for bit, so they can be a grid's layers.
class MovingTarget final : public EnvironmentModel {
 public:
  /// `turnRates`: the turn rates an episode draws one of (rad/s, ascending); empty for
  /// straight lines only (what draw() did before turning targets, random stream included).
  MovingTarget(double minSpeed, double maxSpeed, std::vector<double> turnRates = {})
      : minSpeed_(minSpeed), maxSpeed_(maxSpeed), turnRates_(std::move(turnRates)) {}
  std::string type() const override { return "moving_target"; }
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;
  bool keepsSpeed() const override { return true; }
  TargetState draw(const Eigen::Vector3d& position, Rng& rng) const override;
  double maxSpeed() const override { return maxSpeed_; }
  std::vector<double> turnRates() const override { return turnRates_; }

 private:
  double minSpeed_, maxSpeed_;
  std::vector<double> turnRates_;
};

/// The inverse of transformPoint(): a point of the frame `motion` starts from, seen from
/// the frame it leads to.
Eigen::Vector3d inverseTransformPoint(const GroundMotion& motion, const Eigen::Vector3d& point);

}  // namespace mgrl
