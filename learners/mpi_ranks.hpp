#pragma once
/// \file
/// The processes of an mpi_value_iteration run and how the table is split among
/// them. Only learners/mpi_ranks.cpp sees MPI (a private dependency of the learners
/// library): without MPI, or without a launcher, Ranks is this process alone and makes no
/// MPI call.
#include <exception>
#include <string>
#include <vector>

#include "mgrl/learning/partition.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl::learners {

class Ranks {
 public:
  /// MPI's world when a launcher started this process (MPI is started once, and finalized
  /// at exit), else this process alone. Throws mgrl::Error if a launcher started several
  /// processes of an mgrl built without MPI.
  static Ranks join();

  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Ranks on this machine, which share its cores.
  int localSize() const { return localSize_; }
  bool root() const { return rank_ == 0; }

  /// The largest of each value over all ranks, in place.
  void maxAll(double* values, int n) const;
  /// Rank 0's floats, or text, to every rank.
  void broadcast(float* values, std::size_t n) const;
  void broadcast(std::string& text) const;
  /// Rows of `width` floats: sendCount[d] rows from `send` to rank d (in rank order), and
  /// recvCount[q] rows from rank q into `recv`. With one rank, a copy.
  void exchange(const float* send, const std::vector<int>& sendCount, float* recv, const std::vector<int>& recvCount,
                std::size_t width) const;
  /// Rank 0 puts the block of every state into `whole` (the whole table): its own from
  /// `held`, the others' received from their owners, which send theirs in increasing state
  /// order. A state's block (its actions' rows at every vertex) is contiguous in both.
  /// `whole` is used at rank 0 only; it may be `held` itself when one rank holds everything.
  void gather(QTable& held, QTable& whole, const GridModel& g, const std::vector<int>& owner) const;
  /// The inverse, after rank 0 read a checkpoint: each rank receives its states' blocks.
  void scatter(QTable& whole, QTable& held, const GridModel& g, const std::vector<int>& owner) const;
  /// After an error on this rank, while the others may wait for it: says which rank failed
  /// and ends the whole job (MPI_Abort); alone, returns and the error goes on.
  void failed(const std::exception& e) const;

 private:
  void move(QTable& held, QTable& whole, const GridModel& g, const std::vector<int>& owner, bool toWhole) const;

  bool mpi_ = false;
  int rank_ = 0, size_ = 1, localSize_ = 1;
};

}  // namespace mgrl::learners
