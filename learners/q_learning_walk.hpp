#pragma once
/// \file
/// The two halves of the `q_learning` learner's algorithm (Lee & Lee 2004, sec. 4.2), which
/// its train() runs a chunk of steps at a time: the random walk, which picks each action and
/// moves the target, and the update of every vertex of the target's cell. The walk does not
/// depend on Q, so train() walks a chunk ahead (on a thread of its own when it has two)
/// and updates from the record. Private to learners/.
#include <cstdint>
#include <span>
#include <vector>

#include "mgrl/learning/learner.hpp"
#include "q_learning_checkpoint.hpp"

namespace mgrl::learners {

/// One step of the walk, as the update needs it: the action taken and the target's cell.
struct WalkStep {
  std::uint32_t action, cell;
};

/// The random walk: random poses and targets inside the grid, uniformly random actions, a
/// restart when the target leaves the grid (or after max_episode_actions, beyond the paper).
class QLearningWalk {
 public:
  /// On `context`'s problem and grid model. `cellSeen` (one flag per grid cell) is marked
  /// with every cell the walk is in; it must outlive the walk.
  QLearningWalk(const TrainContext& context, std::uint64_t maxEpisode, std::vector<std::uint8_t>& cellSeen);

  /// A random pose, then a random target inside the grid.
  void restart(Walk& w) const;
  /// Walks `w` on to update `stop`, recording its steps into `steps` and, on a compact
  /// model (GridModel::buildCompact), where each step's corners land into `landed`, 2^d a
  /// step. Consumes the random numbers in the order the paper's interleaved loop would.
  void walkChunk(Walk& w, std::uint64_t stop, std::vector<WalkStep>& steps, std::vector<GridTransition>& landed) const;

 private:
  const StateActionModel& m_;
  const Discretizer& grid_;
  const EnvironmentModel& environment_;
  const GridModel& g_;
  std::uint64_t maxEpisode_;
  std::vector<std::uint8_t>& cellSeen_;
};

/// The update over recorded steps: every corner v of the target's cell,
///     Q(v, a) += alpha (r(v, a) + gamma^t_a max_a' Q(e'_v, a') - Q(v, a)),
/// with alpha falling linearly from 1 at update 0 to alpha_final at update `total`.
class QLearningUpdate {
 public:
  /// Updates `q` (which must outlive this) on grid model `g`.
  QLearningUpdate(const GridModel& g, QTable& q, std::uint64_t total, double alphaFinal);

  /// The updates of `steps` (and `landed`, as walkChunk() recorded them), the first of them
  /// update number `from`. Knowing the steps ahead lets the loop prefetch: the tables are
  /// far bigger than the caches and random actions defeat the hardware's own prefetching.
  void update(const std::vector<WalkStep>& steps, const std::vector<GridTransition>& landed, std::uint64_t from);

 private:
  // The record by value (spans), not through the vectors: see q_learning_walk.cpp.
  template <bool kCompact>
  void update(std::span<const WalkStep> steps, std::span<const GridTransition> landed, std::uint64_t from);

  const GridModel& g_;
  QTable& q_;
  double alphaSlope_;
  std::vector<std::uint64_t> seen_;  ///< rows prefetched for the step at stamp_
  std::uint64_t stamp_ = 0;
};

}  // namespace mgrl::learners
