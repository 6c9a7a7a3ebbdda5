#pragma once
/// \file
/// One rank's share of an mpi_value_iteration run: which states it holds, which actions it
/// backs up, the order of the rows it sends and receives, and the model of its part of the
/// table. Pure bookkeeping over the grid model (no MPI): partitionByEndState()
/// (mgrl/learning/partition.hpp) decides the owner of each state, this file what follows
/// from it for one rank.
#include <cstdint>
#include <vector>

#include "mgrl/learning/problem.hpp"

namespace mgrl::learners {

/// Rank `me`'s share of a run (mpi_value_iteration.cpp says why this split): the states it
/// holds, the actions it backs up, and the order of the rows each rank sends and receives:
/// by the other rank, then by action.
struct RankShare {
  std::vector<int> owner;                     // the rank holding each state
  std::vector<std::uint32_t> mine, theirs;    // backed up here; leaving a state held here
  std::vector<int> sendCount, recvCount;      // rows to and from each rank
  std::vector<std::uint32_t> slot, recvSlot;  // an action's row in `mine`, in `theirs`
  std::vector<std::uint32_t> held;            // this rank's states
  double exchanged = 0;                       // bytes sent to the other ranks a sweep
};

/// Rank `me`'s share of `g` over `ranks` ranks (partitionByEndState()), `actionFrom` the
/// model's start state of each action.
RankShare shareOf(const GridModel& g, const std::vector<std::uint32_t>& actionFrom, int me, int ranks);

/// The model of a table that holds the rows of rank `me`'s states only: the other states
/// have no actions (QTable keeps each state's block contiguous, so row(s, v) of an own
/// state is where backups and maxInterpolated() expect it).
StateActionModel heldModel(const GridModel& g, const std::vector<int>& owner, int me);

}  // namespace mgrl::learners
