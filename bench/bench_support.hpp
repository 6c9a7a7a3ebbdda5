#pragma once
// Shared by the benchmarks: this machine is shared and noisy, so they report medians.
#include <algorithm>
#include <vector>

namespace mgrl::bench {

/// The median of `samples` (the upper one for an even count); `samples` must not be empty.
inline double median(std::vector<double> samples) {
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

}  // namespace mgrl::bench
