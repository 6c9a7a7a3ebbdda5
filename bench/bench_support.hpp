#pragma once
// Shared by the benchmarks: this machine is shared and noisy, so they report medians.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/random.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/runtime/controller.hpp"

namespace mgrl::bench {

/// The median of `samples` (the upper one for an even count); `samples` must not be empty.
inline double median(std::vector<double> samples) {
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

/// Where timed loops leave their results, so that the compiler cannot drop the calls.
inline volatile std::size_t decisionSink = 0;

/// A decision to time: a state and a target in the avatar's frame.
using DecisionQuery = std::pair<std::uint32_t, Eigen::Vector3d>;

/// `count` random decisions, the same for the same seed: any state, a target within 1.5 m
/// in x and z at the effective hitting points' height.
inline std::vector<DecisionQuery> decisionQueries(const StateActionModel& model, std::size_t count = 2000,
                                                  std::uint64_t seed = 3) {
  std::vector<DecisionQuery> queries;
  Rng rng(seed);
  for (std::size_t q = 0; q < count; ++q) {
    const auto s = static_cast<std::uint32_t>(rng.below(model.stateCount()));
    queries.emplace_back(s, Eigen::Vector3d((2 * rng.uniform() - 1) * 1.5, model.centroid[1], (2 * rng.uniform() - 1) * 1.5));
  }
  return queries;
}

/// Seconds per decision of `controller` on the first `count` queries: each run repeats them
/// for at least 0.2 s; the median of `runs` runs.
inline double decisionSeconds(Controller& controller, const std::vector<DecisionQuery>& queries, std::size_t count,
                              int runs) {
  using Clock = std::chrono::steady_clock;
  std::vector<double> samples;
  Rng draws(1);
  for (int r = 0; r < runs; ++r) {
    std::size_t sink = 0, calls = 0;
    const auto start = Clock::now();
    double seconds = 0;
    do {
      for (std::size_t q = 0; q < count; ++q) sink += controller.choose(queries[q].first, queries[q].second, draws);
      calls += count;
      seconds = std::chrono::duration<double>(Clock::now() - start).count();
    } while (seconds < 0.2);
    samples.push_back(seconds / static_cast<double>(calls));
    decisionSink = sink;
  }
  return median(samples);
}

}  // namespace mgrl::bench
