#pragma once
/// \file
/// What a whole scenario shares, whatever behaviour is asked: the one world its behaviours
/// were trained for (the environment model that moves the target and the capabilities it
/// offers, asked for once here; the discount of returns) and the `world:` section's
/// parameters. Built once per session, with one clear error when behaviours disagree.
#include <vector>

#include "mgrl/learning/behavior.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/scenario.hpp"

namespace mgrl {

struct Task {
  /// Moves the target as every behaviour was trained to (the first behaviour's object; the
  /// others' are equal to it). Never null in a Task from makeTask().
  const EnvironmentModel* environment = nullptr;
  /// Returns and the online search discount with it (paper sec. 4: one gamma per scenario).
  double gamma = 0.97;
  /// The environment is an opponent that turns to face the avatar (TargetState::heading):
  /// it offers FacingOpponent.
  bool opponent = false;
  /// Its targets move (TargetMotion: speeds, turn rates); null for targets that stand.
  const TargetMotion* targetMotion = nullptr;
  /// A learned opponent that plays graph actions (TrackedOpponent); null for none.
  const TrackedOpponent* trackedOpponent = nullptr;
  /// trackedOpponent's phases per graph state (TrackedOpponent::opponentPhases()), 0 for none.
  int opponentPhases = 0;
  /// The environment's scripted opponent as the world plays it with graph actions (an
  /// `opponent` model): the second avatar of each sparring pair pursues the first
  /// (PursueController) to `stopDistance`, or takes the actions that move it least
  /// (`stand`). Null for other models.
  using ScriptedOpponent = mgrl::ScriptedOpponent;
  const ScriptedOpponent* scriptedOpponent = nullptr;
  /// The scenario's `world:` section (defaults where absent), parsed once here.
  WorldParams world;

  /// The target height trials use: `given` unless NaN, else world.target_height when set
  /// (>= 0), else NaN (the trials take the effective hitting points' centroid's).
  double targetHeight(double given) const;
};

/// The task of `scenario` and its built `behaviors` (at least one). Throws mgrl::Error at
/// the disagreeing behaviour's block (`file:line:col: behaviors.B.environment: ...`) when
/// two behaviours have different environment models or different gammas.
Task makeTask(const Scenario& scenario, const std::vector<Behavior>& behaviors);
/// The same for behaviours built without a scenario file (tests, Python): the world's
/// parameters are the defaults, and a disagreement is reported as `source: behaviors.B...`.
Task makeTask(const std::vector<Behavior>& behaviors, const std::string& source);

}  // namespace mgrl
