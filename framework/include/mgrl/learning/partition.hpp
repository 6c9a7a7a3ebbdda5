#pragma once
/// \file
/// How a table is split among processes (mpi_value_iteration, DESIGN.md sec. 7): each
/// process owns the graph states it backs up, so that the loads are even.
#include <vector>

#include "mgrl/learning/problem.hpp"

namespace mgrl {

/// Which of `ranks` processes owns each graph state: longest first to the least loaded
/// rank (Graham's LPT rule), the load of a state being the actions that end at it (its
/// backups per vertex). Deterministic.
std::vector<int> partitionByEndState(const GridModel& g, int ranks);

}  // namespace mgrl
