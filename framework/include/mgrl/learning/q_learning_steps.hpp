#pragma once
/// \file
/// The paper's Q-learning (sec. 4.2) one action at a time, for teaching: the viewer's learn
/// panel shows each update as the paper's Fig. 4 draws it. The walk, the update and the
/// table are those of the `q_learning` learner with the same budget, seed and alpha_final
/// (and max_episode_actions 0): after `budget` steps the table is the same, bit for bit.
/// Only the bookkeeping differs: a step computes the transitions of its own (action,
/// vertex) pairs when it is taken, where the learner tabulates every pair first.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/random.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// One grid vertex of the target's cell, updated by one step.
struct QStepVertex {
  std::uint32_t vertex = 0;
  Eigen::Vector3d position{0, 0, 0};  ///< v, in the avatar's frame before the action
  double weight = 0;        ///< v's interpolation weight at the target e (shown, not used: every corner is updated)
  double reward = 0;        ///< r(v, a)
  bool nextInside = false;  ///< e'_v (v moved along by the action) is on the grid
  Eigen::Vector3d next{0, 0, 0};  ///< e'_v, in the avatar's frame after the action
  double discount = 0;            ///< gamma^t for the action's t frames
  double future = 0;              ///< max_a' Q(e'_v, a'), interpolated; 0 off the grid
  double backup = 0;              ///< reward + discount * future
  double before = 0, after = 0;   ///< Q(v, a) before and after the update
};

/// What one step did.
struct QStep {
  std::uint64_t update = 0;  ///< 1 for the first step
  double alpha = 0;          ///< the learning rate of this step
  std::uint32_t state = 0, nextState = 0;
  std::uint32_t action = 0;             ///< index in the model's actions
  std::uint32_t frames = 0;             ///< the action's length
  Eigen::Vector3d target{0, 0, 0};      ///< e, avatar frame before the action
  Eigen::Vector3d targetNext{0, 0, 0};  ///< e', avatar frame after the action
  bool restarted = false;               ///< e' left the grid: the walk restarts at a random pose and target
  std::vector<QStepVertex> vertices;
};

class QLearningSteps {
 public:
  /// Throws mgrl::Error for a grid with hanging vertices (q_learning refuses them too).
  QLearningSteps(const Problem& problem, std::uint64_t budget, std::uint64_t seed, double alphaFinal = 0);

  /// The table's bytes for `problem`, to check before constructing one.
  static double tableBytes(const Problem& problem);

  /// Takes the next action of the walk and updates every vertex of the target's cell.
  /// Throws mgrl::Error once the budget is spent.
  QStep step();

  bool done() const { return updates_ >= budget_; }
  std::uint64_t updates() const { return updates_; }
  std::uint64_t budget() const { return budget_; }
  std::uint64_t restarts() const { return restarts_; }
  /// (action, vertex) entries updated at least once.
  std::size_t touched() const { return touched_; }
  std::uint32_t state() const { return state_; }
  const Eigen::Vector3d& target() const { return target_.position; }
  const QTable& table() const { return table_; }
  const GridModel& grid() const { return frame_; }

 private:
  void restart();

  Problem problem_;
  GridModel frame_;
  QTable table_;
  std::vector<TargetState> vertex_;
  std::vector<std::uint8_t> seen_;  ///< per (action, vertex): updated at least once
  std::uint64_t budget_, updates_ = 0, restarts_ = 0;
  std::size_t touched_ = 0;
  double alphaSlope_;
  Rng rng_;
  std::uint32_t state_ = 0;
  TargetState target_;
};

}  // namespace mgrl
