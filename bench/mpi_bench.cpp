// How much a value-iteration sweep must exchange when the table is split across
// K ranks, for the split mpi_value_iteration uses (by graph state) and for the obvious
// alternative (by blocks of grid vertices; on a learned-opponent grid, whose vertices are
// numbered layer by layer, that is also the split by opponent state). Counted exactly on
// the tabulated problem, not timed: scripts/mpi_scaling.py times the real runs under
// mpirun and puts both together.
//
//   mgrl_bench_mpi SCENARIO BEHAVIOR [--set KEY=VALUE]... [--ranks 2,4,16,64]
//
// Prints one JSON object: the table's size and, per K and split, the bytes received per
// sweep by the busiest rank and by all ranks together.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "builtin_plugins.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/learning/partition.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/session/session.hpp"

using namespace mgrl;
using nlohmann::json;

namespace {

struct Volume {
  double busiest = 0, total = 0;  // bytes received per sweep
};

// By graph state: a rank receives the new values of the actions leaving its states that
// other ranks backed up (those ending at their states): V floats per such action.
Volume byState(const GridModel& g, int ranks) {
  const std::vector<int> owner = partitionByEndState(g, ranks);
  std::vector<double> received(static_cast<std::size_t>(ranks), 0);
  const std::size_t states = g.incomingBegin.size() - 1;
  for (std::size_t s = 0; s < states; ++s)
    for (std::uint32_t a = g.stateActionBegin[s]; a < g.stateActionBegin[s + 1]; ++a)
      if (owner[g.actionTo[a]] != owner[s])
        received[static_cast<std::size_t>(owner[s])] += static_cast<double>(g.vertexCount) * sizeof(float);
  Volume v;
  for (double r : received) v.busiest = std::max(v.busiest, r), v.total += r;
  return v;
}

// By vertex blocks: rank r backs up every action at its vertices [rV/K, (r+1)V/K) and
// holds every state's rows there; a backup reads the rows of its end state at the corners
// of its landing cell, and a corner outside the block is a row (n_s floats) received.
Volume byVertexBlock(const GridModel& g, int ranks, unsigned threads) {
  const std::size_t V = g.vertexCount, states = g.incomingBegin.size() - 1;
  const std::size_t corners = std::size_t{1} << g.dimension;
  std::vector<double> received(static_cast<std::size_t>(ranks), 0);
  parallelFor(static_cast<std::size_t>(ranks), threads, [&](std::size_t r, unsigned) {
    const std::size_t first = r * V / static_cast<std::size_t>(ranks),
                      last = (r + 1) * V / static_cast<std::size_t>(ranks);
    std::vector<std::uint8_t> needed(states * V, 0);
    for (std::size_t a = 0; a < g.actionCount; ++a) {
      const std::size_t s = g.actionTo[a];
      for (std::size_t v = first; v < last; ++v) {
        const GridTransition& t = g.transition[a * V + v];
        if (t.cell < 0) continue;
        for (std::size_t k = 0; k < corners; ++k) {
          const std::uint32_t w = g.corners[(static_cast<std::size_t>(t.cell) << g.dimension) + k];
          if (w < first || w >= last) needed[s * V + w] = 1;
        }
      }
    }
    double bytes = 0;
    for (std::size_t s = 0; s < states; ++s) {
      const double row = static_cast<double>(g.stateActionBegin[s + 1] - g.stateActionBegin[s]) * sizeof(float);
      for (std::size_t w = 0; w < V; ++w)
        if (needed[s * V + w]) bytes += row;
    }
    received[r] = bytes;
  });
  Volume v;
  for (double r : received) v.busiest = std::max(v.busiest, r), v.total += r;
  return v;
}

std::vector<int> parseRanks(const std::string& text) {
  std::vector<int> out;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const std::string piece = text.substr(at, comma - at);
    int k = 0;
    if (std::sscanf(piece.c_str(), "%d", &k) != 1 || k < 1 || k > 4096)
      throw Error(fmt::format("--ranks: expected whole numbers from 1 to 4096 separated by commas, found '{}'", piece));
    out.push_back(k);
    at = comma + 1;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 3) {
      std::cerr << "usage: mgrl_bench_mpi SCENARIO BEHAVIOR [--set KEY=VALUE]... [--ranks 2,4,16,64]\n";
      return 2;
    }
    SessionOptions options;
    options.scenario = argv[1];
    options.plugins = &builtinPlugins();
    const std::string behaviorName = argv[2];
    std::vector<int> ranks = {2, 4, 16, 64};
    for (int i = 3; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--set" && i + 1 < argc)
        options.sets.push_back(argv[++i]);
      else if (arg == "--ranks" && i + 1 < argc)
        ranks = parseRanks(argv[++i]);
      else
        throw Error(fmt::format("expected --set KEY=VALUE or --ranks LIST, found '{}'", arg));
    }
    SessionNeeds needs;
    needs.motion = false;
    const std::unique_ptr<const Session> session = openSession(options, needs);
    const auto found = std::find_if(session->behaviors.begin(), session->behaviors.end(),
                                    [&](const Behavior& b) { return b.name == behaviorName; });
    if (found == session->behaviors.end())
      throw Error(fmt::format("{}: expected one of the scenario's behaviours, found '{}'", argv[1], behaviorName));
    const unsigned threads = defaultThreadCount();
    const Problem problem = found->problem(session->model());
    const GridModel g = GridModel::build(problem, threads);
    json out = {{"scenario", argv[1]},
                {"behavior", behaviorName},
                {"vertices", g.vertexCount},
                {"actions", g.actionCount},
                {"states", g.incomingBegin.size() - 1},
                {"table_bytes", static_cast<double>(g.vertexCount) * g.actionCount * sizeof(float)},
                {"splits", json::array()}};
    for (int k : ranks) {
      const Volume state = byState(g, k), block = byVertexBlock(g, k, threads);
      out["splits"].push_back(
          {{"ranks", k},
           {"by_graph_state", {{"busiest_rank_bytes", state.busiest}, {"total_bytes", state.total}}},
           {"by_vertex_block", {{"busiest_rank_bytes", block.busiest}, {"total_bytes", block.total}}}});
    }
    std::cout << out.dump(2) << '\n';
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "mgrl_bench_mpi: " << e.what() << '\n';
    return 1;
  }
}
