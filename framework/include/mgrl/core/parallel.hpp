#pragma once
/// \file
/// A minimal parallel loop over independent tasks on std::threads (no OpenMP: sanitizers
/// and a bare machine both cope with plain threads).
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace mgrl {

/// Threads to use by default: the hardware's, at least 1.
inline unsigned defaultThreadCount() { return std::max(1u, std::thread::hardware_concurrency()); }

/// Calls `task(i, worker)` once for every i in [0, count) on up to `threads` threads
/// (worker in [0, threads) names the calling thread, for per-thread scratch). Tasks are
/// handed out in order from a shared counter; results written by index are therefore
/// deterministic whatever the scheduling. The first exception thrown by a task is rethrown
/// here after every thread has stopped.
template <class Task>
void parallelFor(std::size_t count, unsigned threads, Task&& task) {
  threads = std::max(1u, std::min<unsigned>(threads, static_cast<unsigned>(std::max<std::size_t>(count, 1))));
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failureMutex;
  auto work = [&](unsigned worker) {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= count) return;
      try {
        task(i, worker);
      } catch (...) {
        const std::lock_guard lock(failureMutex);
        if (!failure) failure = std::current_exception();
        next = count;
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < threads; ++w) pool.emplace_back(work, w);
  work(0);
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace mgrl
