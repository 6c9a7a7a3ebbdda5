// Ranks and the split of mpi_value_iteration (learners/mpi_ranks.hpp): the only file
// that calls MPI (Open MPI's C API, when CMake found it: MGRL_HAVE_MPI).
#include "mpi_ranks.hpp"

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <numeric>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/launch.hpp"

#if MGRL_HAVE_MPI
#include <mpi.h>
#endif

namespace mgrl::learners {

Ranks Ranks::join() {
  Ranks r;
  const LaunchedProcess launched = launchedProcess();
#if MGRL_HAVE_MPI
  if (launched.byLauncher) {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      int provided = 0;
      MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
      std::atexit([] {
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (!finalized) MPI_Finalize();
      });
    }
    r.mpi_ = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &r.rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &r.size_);
    MPI_Comm local;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, r.rank_, MPI_INFO_NULL, &local);
    MPI_Comm_size(local, &r.localSize_);
    MPI_Comm_free(&local);
  }
#else
  if (launched.byLauncher && launched.size > 1)
    throw Error(
        fmt::format("mpi_value_iteration: started as rank {} of {} by an MPI launcher, but this mgrl was "
                    "built without MPI (install libopenmpi-dev and rebuild)",
                    launched.rank, launched.size));
#endif
  return r;
}

// The largest of each value over all ranks, in place.
void Ranks::maxAll(double* values, int n) const {
#if MGRL_HAVE_MPI
  if (mpi_ && size_ > 1) MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
#endif
  (void)values, (void)n;
}

// Rank 0's floats to every rank, in pieces that an int counts.
void Ranks::broadcast(float* values, std::size_t n) const {
#if MGRL_HAVE_MPI
  if (!mpi_ || size_ == 1) return;
  constexpr std::size_t kPiece = std::size_t{1} << 28;
  for (std::size_t at = 0; at < n; at += kPiece)
    MPI_Bcast(values + at, static_cast<int>(std::min(kPiece, n - at)), MPI_FLOAT, 0, MPI_COMM_WORLD);
#endif
  (void)values, (void)n;
}
void Ranks::broadcast(std::string& text) const {
#if MGRL_HAVE_MPI
  if (!mpi_ || size_ == 1) return;
  unsigned long long n = text.size();
  MPI_Bcast(&n, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  text.resize(n);
  MPI_Bcast(text.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
#endif
  (void)text;
}

// Rows of `width` floats: sendCount[d] rows from `send` to rank d (in rank order), and
// recvCount[q] rows from rank q into `recv`. With one rank, a copy.
void Ranks::exchange(const float* send, const std::vector<int>& sendCount, float* recv,
                     const std::vector<int>& recvCount, std::size_t width) const {
#if MGRL_HAVE_MPI
  if (mpi_ && size_ > 1) {
    MPI_Datatype row;
    MPI_Type_contiguous(static_cast<int>(width), MPI_FLOAT, &row);
    MPI_Type_commit(&row);
    std::vector<int> sendAt(size_), recvAt(size_);
    std::exclusive_scan(sendCount.begin(), sendCount.end(), sendAt.begin(), 0);
    std::exclusive_scan(recvCount.begin(), recvCount.end(), recvAt.begin(), 0);
    MPI_Alltoallv(send, sendCount.data(), sendAt.data(), row, recv, recvCount.data(), recvAt.data(), row,
                  MPI_COMM_WORLD);
    MPI_Type_free(&row);
    return;
  }
#endif
  std::copy(send, send + static_cast<std::size_t>(sendCount[0]) * width, recv);
  (void)recvCount;
}

// Rank 0 puts the block of every state into `whole` (the whole table): its own from
// `held`, the others' received from their owners, which send theirs in increasing
// state order. A state's block (its actions' rows at every vertex) is contiguous in both.
void Ranks::gather(QTable& held, QTable& whole, const GridModel& g, const std::vector<int>& owner) const {
  move(held, whole, g, owner, true);
}
// The inverse, after rank 0 read a checkpoint: each rank receives its states' blocks.
void Ranks::scatter(QTable& whole, QTable& held, const GridModel& g, const std::vector<int>& owner) const {
  move(held, whole, g, owner, false);
}

// After an error on this rank, while the others may wait for it: says which rank failed
// and ends the whole job (MPI_Abort), or, alone, lets the error go on.
void Ranks::failed(const std::exception& e) const {
#if MGRL_HAVE_MPI
  if (mpi_ && size_ > 1) {
    std::cerr << fmt::format("mgrl: mpi_value_iteration: rank {} of {}: {}\n", rank_, size_, e.what());
    std::cerr.flush();
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
#endif
  (void)e;
}

// `whole` is read or written at rank 0 only (elsewhere it may be empty); the same object
// as `held` when one rank holds everything.
void Ranks::move(QTable& held, QTable& whole, const GridModel& g, const std::vector<int>& owner, bool toWhole) const {
  if (&held == &whole) return;
  const std::size_t V = held.vertexCount();
  for (std::size_t s = 0; s < owner.size(); ++s) {
    const std::size_t actions = g.stateActionBegin[s + 1] - g.stateActionBegin[s], n = actions * V;
    if (n == 0) continue;
    if (owner[s] == rank_ && rank_ == 0) {
      if (toWhole)
        std::copy_n(held.row(s, 0), n, whole.row(s, 0));
      else
        std::copy_n(whole.row(s, 0), n, held.row(s, 0));
      continue;
    }
#if MGRL_HAVE_MPI
    if (!mpi_) continue;
    MPI_Datatype row;
    MPI_Type_contiguous(static_cast<int>(V), MPI_FLOAT, &row);
    MPI_Type_commit(&row);
    const int rows = static_cast<int>(actions), tag = static_cast<int>(s % 32768);
    if (toWhole) {
      if (rank_ == 0)
        MPI_Recv(whole.row(s, 0), rows, row, owner[s], tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      else if (owner[s] == rank_)
        MPI_Send(held.row(s, 0), rows, row, 0, tag, MPI_COMM_WORLD);
    } else {
      if (rank_ == 0)
        MPI_Send(whole.row(s, 0), rows, row, owner[s], tag, MPI_COMM_WORLD);
      else if (owner[s] == rank_)
        MPI_Recv(held.row(s, 0), rows, row, 0, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
    MPI_Type_free(&row);
#endif
  }
}

}  // namespace mgrl::learners
