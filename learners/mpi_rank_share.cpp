// One rank's share of an mpi_value_iteration run (mpi_rank_share.hpp).
#include "mpi_rank_share.hpp"

#include <algorithm>

#include "mpi_ranks.hpp"

namespace mgrl::learners {

RankShare shareOf(const GridModel& g, const std::vector<std::uint32_t>& actionFrom, int me, int ranks) {
  const std::vector<std::uint32_t>& from = actionFrom;
  const int K = ranks;
  const std::size_t V = g.vertexCount, A = g.actionCount;
  const std::size_t states = g.incomingBegin.size() - 1;
  RankShare share;
  share.owner = partitionByEndState(g, K);
  const std::vector<int>& owner = share.owner;
  std::vector<std::uint32_t>& mine = share.mine;
  std::vector<std::uint32_t>& theirs = share.theirs;
  for (std::uint32_t a = 0; a < A; ++a) {
    if (owner[g.actionTo[a]] == me) mine.push_back(a);
    if (owner[from[a]] == me) theirs.push_back(a);
  }
  std::stable_sort(mine.begin(), mine.end(), [&](auto x, auto y) { return owner[from[x]] < owner[from[y]]; });
  std::stable_sort(theirs.begin(), theirs.end(),
                   [&](auto x, auto y) { return owner[g.actionTo[x]] < owner[g.actionTo[y]]; });
  std::vector<int>& sendCount = share.sendCount;
  std::vector<int>& recvCount = share.recvCount;
  sendCount.assign(K, 0);
  recvCount.assign(K, 0);
  std::vector<std::uint32_t>& slot = share.slot;
  std::vector<std::uint32_t>& recvSlot = share.recvSlot;
  slot.assign(A, 0);
  recvSlot.assign(A, 0);
  for (std::size_t i = 0; i < mine.size(); ++i) {
    ++sendCount[owner[from[mine[i]]]];
    slot[mine[i]] = static_cast<std::uint32_t>(i);
  }
  for (std::size_t i = 0; i < theirs.size(); ++i) {
    ++recvCount[owner[g.actionTo[theirs[i]]]];
    recvSlot[theirs[i]] = static_cast<std::uint32_t>(i);
  }
  for (std::size_t s = 0; s < states; ++s)
    if (owner[s] == me) share.held.push_back(static_cast<std::uint32_t>(s));
  std::uint64_t sentRows = 0;
  for (int d = 0; d < K; ++d)
    if (d != me) sentRows += static_cast<std::uint64_t>(sendCount[d]);
  share.exchanged = static_cast<double>(sentRows) * static_cast<double>(V) * sizeof(float);
  return share;
}

StateActionModel heldModel(const GridModel& g, const std::vector<int>& owner, int me) {
  const std::size_t states = g.incomingBegin.size() - 1;
  StateActionModel held;
  held.stateFrame.assign(states, 0);
  held.stateActionBegin.assign(states + 1, 0);
  for (std::size_t s = 0; s < states; ++s)
    held.stateActionBegin[s + 1] =
        held.stateActionBegin[s] + (owner[s] == me ? g.stateActionBegin[s + 1] - g.stateActionBegin[s] : 0);
  held.actionFrom.assign(held.stateActionBegin.back(), 0);
  return held;
}

}  // namespace mgrl::learners
