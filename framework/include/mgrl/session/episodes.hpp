#pragma once
/// \file
/// One behaviour's problem played as episodes, many at once (Python's MotionGraphEnv and
/// its vectorised form): the avatar in a graph state with the target somewhere
/// in the behaviour's grid, in the avatar's frame. A step plays one of the state's
/// out-actions; the reward is the behaviour's reward for that action from that target
/// (paper sec. 4.1, evaluated at the target itself, not at grid vertices), the target then
/// moves as the behaviour's environment model moves it (sec. 4.2) and the avatar lands in
/// the action's end state.
///
/// An episode starts as Q-learning's walks restart (a uniformly drawn state, a target
/// uniform in the grid's coordinates and inside it), ends (terminated) when the target
/// leaves the grid, where the tabulated problem counts no future value, or, with
/// `endOnSuccess`, when the behaviour's success criterion is met; and is cut (truncated)
/// once `seconds` of motion have played. Each episode slot has its own random stream. A
/// caller may place an episode's start (EpisodeStart: the state, the target's position).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/random.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/success.hpp"

namespace mgrl {

struct EpisodeOptions {
  double seconds = 10;        ///< motion per episode before it is truncated
  bool endOnSuccess = false;  ///< a met success criterion terminates the episode
};

/// Where reset() places an episode (MotionGraphEnv.reset's options); what is left empty
/// starts as an unplaced episode does. The messages of a bad value name the options.
struct EpisodeStart {
  /// The avatar's graph state, in [0, stateCount()).
  std::optional<std::int64_t> state = std::nullopt;
  /// The target's position in the avatar's frame (x, y, z, m; finite), as observe() writes
  /// it. It may lie outside the grid (the first step then terminates). The target's other
  /// fields (a moving target's speed, heading and turn rate, an opponent's facing or
  /// discrete state) are drawn as for an unplaced start, at this position.
  std::optional<Eigen::Vector3d> target = std::nullopt;
};

/// What one step did, per slot.
struct EpisodeStep {
  float reward = 0;
  bool terminated = false, truncated = false;
  bool success = false;  ///< the behaviour's success criterion was met during the action
};

/// Where an episode ended, as observe() writes it, before stepAll() started its slot anew:
/// what a learner bootstraps from at a truncated end.
struct EpisodeEnd {
  std::int32_t state = 0;
  float position[3] = {0, 0, 0};
  float coordinates[3] = {0, 0, 0};  ///< the first dimension() are set
};

class Episodes {
 public:
  /// `count` slots on `model` for `behavior` (both must outlive this). Throws mgrl::Error
  /// for a count outside [1, 1000000] or options out of range.
  Episodes(const StateActionModel& model, const Behavior& behavior, std::size_t count, const EpisodeOptions& options);

  std::size_t count() const { return slots_.size(); }
  /// The most out-actions any state has: the action space's size.
  std::size_t maxActions() const { return maxActions_; }
  /// The behaviour grid's dimension (coordinates per target).
  int dimension() const { return dimension_; }

  /// Starts slot i's episode, its random stream seeded with `seed` when given, placed as
  /// `at` says. A placed start draws the same random numbers as an unplaced one and puts
  /// what was placed in place of what was drawn, so the slot's stream goes on alike, placed
  /// or not. Throws mgrl::Error, before changing the slot, for a state out of range or a
  /// target not finite.
  void reset(std::size_t i, std::optional<std::uint64_t> seed = std::nullopt, const EpisodeStart& at = {});
  /// Plays out-action `choice` of slot i's state. Throws mgrl::Error (naming `where`, the
  /// slot and the state's action count) unless choice < actionsAt(i).
  EpisodeStep step(std::size_t i, std::size_t choice);
  /// Steps every slot with `choices[i]`; a slot whose episode ended starts a new one at
  /// once (its observation is the new episode's), and where it ended goes to `ends[i]`
  /// when `ends` is given (slots whose episode goes on leave theirs as it was). Every
  /// choice is checked before any slot moves.
  void stepAll(const std::int64_t* choices, EpisodeStep* out, EpisodeEnd* ends = nullptr);

  std::uint32_t state(std::size_t i) const { return slots_[i].state; }
  const TargetState& target(std::size_t i) const { return slots_[i].target; }
  std::size_t actionsAt(std::size_t i) const {
    return model_.stateActionBegin[slots_[i].state + 1] - model_.stateActionBegin[slots_[i].state];
  }
  /// The global action index of slot i's out-action `choice`.
  std::size_t action(std::size_t i, std::size_t choice) const {
    return model_.stateActionBegin[slots_[i].state] + choice;
  }
  /// Seconds of motion played in slot i's episode.
  double seconds(std::size_t i) const { return slots_[i].frames * model_.frameTime; }
  /// Writes slot i's observation: its state, the target's position (x, y, z, avatar frame,
  /// m), its grid coordinates (dimension() values), and maxActions() mask bytes (1 for the
  /// state's out-actions). Any pointer may be null.
  void observe(std::size_t i, std::int32_t* state, float* position, float* coordinates, std::uint8_t* mask) const;

  const StateActionModel& model() const { return model_; }
  const Behavior& behavior() const { return behavior_; }

 private:
  struct Slot {
    Rng rng;
    std::uint32_t state = 0;
    TargetState target;
    std::uint64_t frames = 0;
    std::vector<SuccessCriterion::Tracker> trackers;
  };
  void start(Slot& slot, const EpisodeStart& at = {});
  const StateActionModel& model_;
  const Behavior& behavior_;
  const TrackedOpponent* opponent_ = nullptr;  ///< the behaviour's learned opponent, if it has one
  EpisodeOptions options_;
  double frameLimit_ = 0;
  std::size_t maxActions_ = 0;
  int dimension_ = 0;
  std::vector<Slot> slots_;
};

}  // namespace mgrl
