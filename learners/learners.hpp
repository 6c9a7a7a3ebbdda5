#pragma once
/// \file
/// The learner plugins: `q_learning` (the paper's algorithm, sec. 4.2), `value_iteration`
/// (the same backup swept to convergence: the exact answer on the grid),
/// `adaptive_value_iteration` (value iteration that refines a kd_tree grid where it
/// matters) and `mpi_value_iteration` (value iteration over MPI ranks). What they share.
#include "mgrl/learning/learner.hpp"

namespace mgrl::learners {

/// Adds the four, in the order `mgrl list` shows them (register.cpp).
void registerAll(LearnerRegistry& registry);

/// The `threads` parameter every learner takes (0: the command's --threads).
ParamSpec threadsSpec();

/// Each learner's own registration, in its file.
void registerQLearning(LearnerRegistry& registry);
void registerValueIteration(LearnerRegistry& registry);
void registerAdaptiveValueIteration(LearnerRegistry& registry);
void registerMpiValueIteration(LearnerRegistry& registry);

}  // namespace mgrl::learners
