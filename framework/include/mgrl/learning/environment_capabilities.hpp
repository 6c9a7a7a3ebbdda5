#pragma once
/// \file
/// What an environment model may offer beyond the EnvironmentModel seam: each an ability
/// of one or two models, which the code that needs it asks for once, with
/// EnvironmentModel::as<C>() (null when the model does not offer it). A model offers a
/// marker or an interface by deriving from it, data by holding it, and names each in its
/// capability() override. The conformance suite (tests/conformance_test.cpp) holds every
/// registered model to the contract of each capability it offers.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

class QTable;
class Discretizer;

/// A target that stays put in the world (`static_target`): next() is exactly
/// inverseTransformPoint(model.displacement(action), e.position) with speed 0, so learners
/// may apply it from precomputed sines and cosines (GridModel::rigid).
struct RigidTarget {};

/// Targets that move (`moving_target`): draw() gives each episode a motion (a speed of at
/// most maxSpeed, a direction, one of turnRates), and next() keeps the speed and the turn
/// rate bit for bit, as a grid with speed or turn-rate layers requires.
struct TargetMotion {
  /// The fastest target draw() gives, m/s (the top of a grid's speed layers); 0: the
  /// targets stand, and the runtime world does not move its own.
  double maxSpeed = 0;
  /// The turn rates (rad/s, ascending) draw() picks one of per episode and next() keeps
  /// (turning targets): the behaviour's grid gets one layer per rate
  /// (Discretizer::setTurnLayers). Empty for targets that go straight.
  std::vector<double> turnRates;
};

/// An opponent that turns to face the avatar (`opponent`, `learned_opponent`): the state's
/// heading is which way it faces, not where it moves (its speed is 0), so its grid must hold
/// a heading, the world supplies it (a sparring partner's facing, a dragged target's toward
/// the avatar), and trials report the spacing to it.
struct FacingOpponent {};

/// A scripted opponent fighter (`opponent`), as the runtime world and trials against an
/// avatar play it with graph actions: the second avatar of a pair pursues the first to
/// `stopDistance`, or takes the actions that move it least (`stand`). A model offering it
/// is a FacingOpponent too.
struct ScriptedOpponent {
  bool stand = false;
  double stopDistance = 0;  ///< m, on the ground
};

/// An opponent that plays graph actions of its own (`learned_opponent`): an avatar
/// of the same graph whose discrete state (the graph state its action ends at and a phase)
/// is TargetState::opponent, one grid layer each, and whose body and strikes during an
/// action the rewards, success criteria and self-play's episodes read frame by frame.
class TrackedOpponent {
 public:
  /// The number of discrete opponent states (the layers the grid gets): the bound graph's
  /// states x opponentPhases(). Known after the model's bind(); throws mgrl::Error before it.
  virtual std::size_t opponentStates() const = 0;
  /// The phase buckets per graph state of those (opponentStateIndex()): what the runtime
  /// world needs to tell a controller what a sparring partner is doing.
  virtual int opponentPhases() const = 0;
  /// What the opponent does at frames 1..L of action a from e: out[t - 1] for frame t, L
  /// entries (out is cleared first).
  virtual void track(const StateActionModel& model, std::size_t action, const TargetState& e,
                     std::vector<OpponentFrame>& out) const = 0;

 protected:
  ~TrackedOpponent() = default;
};

/// An opponent that plays a policy table (`learned_opponent`): the bundle the scenario names
/// for it, or in self-play the same behaviour's earlier rounds (round k's opponent plays
/// round k - 1's table). A model offering it is a TrackedOpponent too.
class SelfPlayOpponent {
 public:
  /// Makes the opponent play `table` on `grid` (the same grid, opponent layers included, as
  /// the behaviour's own; it must outlive the model); a null table: its scripted policy.
  /// `key` names the table for messages and records. Throws mgrl::Error for a table of
  /// another shape.
  virtual void playPolicy(const Discretizer* grid, std::shared_ptr<const QTable> table, const std::string& key) = 0;
  /// What the opponent plays, for messages and records: the key playPolicy() was given, or
  /// what it plays without a table ("scripted").
  virtual std::string policyKey() const = 0;
  /// The policy bundle directory the scenario asks the opponent to play, "" for its
  /// scripted policy; buildBehavior() loads it and calls playPolicy().
  virtual std::string policySource() const = 0;
  /// Self-play rounds `mgrl train` runs, at least 1.
  virtual int rounds() const = 0;
  /// True when round k's opponent plays the mean of rounds 1..k - 1's tables instead of
  /// round k - 1's alone (a stand-in for fictitious self-play).
  virtual bool roundsAgainstAverage() const = 0;

 protected:
  ~SelfPlayOpponent() = default;
};

}  // namespace mgrl
