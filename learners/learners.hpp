#pragma once
/// \file
/// The learner plugins: `q_learning` (the paper's algorithm, sec. 4.2) and
/// `value_iteration` (the same backup swept to convergence: the exact answer on the grid).
#include "mgrl/learning/learner.hpp"

namespace mgrl::learners {

/// Adds q_learning, value_iteration, adaptive_value_iteration and mpi_value_iteration.
void registerAll(LearnerRegistry& registry);
void registerQLearning(LearnerRegistry& registry);
void registerValueIteration(LearnerRegistry& registry);
void registerAdaptiveValueIteration(LearnerRegistry& registry);
void registerMpiValueIteration(LearnerRegistry& registry);

/// The `threads` parameter both learners share.
ParamSpec threadsSpec();

}  // namespace mgrl::learners
