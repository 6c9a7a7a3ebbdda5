#include "mgrl/learning/partition.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace mgrl {

std::vector<int> partitionByEndState(const GridModel& g, int ranks) {
  const std::size_t states = g.incomingBegin.size() - 1;
  std::vector<std::size_t> order(states);
  std::iota(order.begin(), order.end(), 0);
  auto work = [&](std::size_t s) { return g.incomingBegin[s + 1] - g.incomingBegin[s]; };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return work(x) > work(y); });
  std::vector<std::uint64_t> load(static_cast<std::size_t>(ranks), 0);
  std::vector<int> owner(states, 0);
  for (std::size_t s : order) {
    const auto least = std::min_element(load.begin(), load.end()) - load.begin();
    owner[s] = static_cast<int>(least);
    load[static_cast<std::size_t>(least)] += work(s);
  }
  return owner;
}

}  // namespace mgrl
