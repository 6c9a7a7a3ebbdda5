// q_learning's walk and update (q_learning_walk.hpp), Lee & Lee 2004 sec. 4.2: the random
// walk that picks the actions and the targets, and the update of every vertex of the
// target's cell. q_learning_steps.cpp takes the same walk and update one step at a time.
#include "learners/q_learning_walk.hpp"

namespace mgrl::learners {

QLearningWalk::QLearningWalk(const TrainContext& context, std::uint64_t maxEpisode, std::vector<std::uint8_t>& cellSeen)
    : m_(context.problem.model),
      grid_(context.problem.grid),
      environment_(context.problem.environment),
      g_(context.grid),
      maxEpisode_(maxEpisode),
      cellSeen_(cellSeen) {}

void QLearningWalk::restart(Walk& w) const {
  w.state = static_cast<std::uint32_t>(w.rng.below(m_.stateCount()));
  do w.target = grid_.sample(w.rng);
  while (!grid_.inside(w.target));
  ++w.restarts;
  w.episodeActions = 0;
}

void QLearningWalk::walkChunk(Walk& w, std::uint64_t stop, std::vector<WalkStep>& steps,
                              std::vector<GridTransition>& landed) const {
  const StateActionModel& m = m_;
  const Discretizer& grid = grid_;
  const EnvironmentModel& environment = environment_;
  const GridModel& g = g_;
  std::vector<std::uint8_t>& cellSeen = cellSeen_;
  const std::uint64_t maxEpisode = maxEpisode_;
  const int d = g.dimension;
  const int corners = 1 << d;
  const bool rigid = !g.rigid.empty();
  const bool compact = g.compact();
  const std::uint32_t* stateBegin = m.stateActionBegin.data();
  steps.clear();
  landed.clear();
  GridCell cell;
  if (!grid.locate(w.target, cell)) {  // only on the boundary's round-off
    restart(w);
    grid.locate(w.target, cell);
  }
  for (std::uint64_t k = w.updates; k < stop; ++k) {
    const std::uint32_t s = w.state;
    const std::size_t a = stateBegin[s] + static_cast<std::uint32_t>(w.rng.below(stateBegin[s + 1] - stateBegin[s]));
    steps.push_back({static_cast<std::uint32_t>(a), cell.cell});
    cellSeen[cell.cell] = 1;
    if (compact) {
      const std::uint32_t* c = &g.corners[static_cast<std::size_t>(cell.cell) << d];
      for (int j = 0; j < corners; ++j) landed.push_back(g.moved(a, c[j]));
    }
    w.target = rigid ? g.rigidNext(a, w.target) : environment.next(m, a, w.target);
    w.state = m.actionTo[a];
    ++w.episodeActions;
    // The paper restarts when the target leaves the grid (sec. 4.2); a cap on the
    // episode also restarts a walk whose avatar hardly travels, which would otherwise
    // keep the target in a few cells for the whole budget.
    if (!grid.locate(w.target, cell) || (maxEpisode > 0 && w.episodeActions >= maxEpisode)) {
      restart(w);
      grid.locate(w.target, cell);
    }
  }
  w.updates = stop;
}

QLearningUpdate::QLearningUpdate(const GridModel& g, QTable& q, std::uint64_t total, double alphaFinal)
    : g_(g), q_(q), alphaSlope_((1 - alphaFinal) / static_cast<double>(total)), seen_(g.vertexCount, 0) {}

// Compiled once per kind of model, so the tabulated loop carries no test of the model's
// kind. A compact model stores no transitions: the walk found where each step's corners
// land (`landed`, in order), and the rewards, like Q, come from the model's table.
//
// The record comes as spans and the prefetch stamps as a pointer, held here: the backups
// call out of this file, after which anything read through a vector (its data pointer,
// its size) would be read again, once a backup. Those vectors sit in train()'s frame right
// beside the ones the walk is filling on the other thread, which stores to theirs at
// every step; whenever the stack's alignment put both on one cache line, the line went
// back and forth between the cores and approach's Q-learning took 1.2 to 1.6 times as
// long on two threads (a run's stack alignment is random, so about every other run).
template <bool kCompact>
void QLearningUpdate::update(std::span<const WalkStep> steps, std::span<const GridTransition> landed,
                             std::uint64_t from) {
  const GridModel& g = g_;
  QTable& q = q_;
  std::uint64_t* const seen = seen_.data();  // rows prefetched for the step at `stamp`
  std::uint64_t stamp = stamp_;
  const double alphaSlope = alphaSlope_;
  const int d = g.dimension;
  const int corners = 1 << d;
  constexpr std::size_t kTransitionAhead = 6, kRowsAhead = 3;
  // Step i's corner j: from the table, or as the walk found it (compact models; the
  // reward is not needed there).
  auto transition = [&](std::size_t i, const std::uint32_t* c, int j) -> const GridTransition& {
    if constexpr (kCompact)
      return landed[i * static_cast<std::size_t>(corners) + static_cast<std::size_t>(j)];
    else
      return g.transition[steps[i].action * g.vertexCount + c[j]];
  };
  const std::size_t count = steps.size();
  for (std::size_t i = 0; i < count; ++i) {
    if (i + kTransitionAhead < count) {
      const WalkStep& ahead = steps[i + kTransitionAhead];
      const std::uint32_t* c = &g.corners[static_cast<std::size_t>(ahead.cell) << d];
      for (int j = 0; j < corners; ++j) {
        if constexpr (kCompact)
          __builtin_prefetch(&g.reward[ahead.action * g.vertexCount + c[j]]);
        else
          __builtin_prefetch(&g.transition[ahead.action * g.vertexCount + c[j]]);
        __builtin_prefetch(&q.at(ahead.action, c[j]), 1);
      }
    }
    if (i + kRowsAhead < count) {
      // The rows the backups of that step will interpolate: its transitions should be
      // in cache by now.
      const WalkStep& ahead = steps[i + kRowsAhead];
      const std::uint32_t* c = &g.corners[static_cast<std::size_t>(ahead.cell) << d];
      const std::uint32_t to = g.actionTo[ahead.action];
      const std::size_t n = q.actionsOf(to);
      ++stamp;
      for (int j = 0; j < corners; ++j) {
        const GridTransition& t = transition(i + kRowsAhead, c, j);
        if (t.cell < 0) continue;
        const std::uint32_t* u = &g.corners[static_cast<std::size_t>(t.cell) << d];
        for (int l = 0; l < corners; ++l) {
          // The moved corners' cells overlap: each row once.
          if (seen[u[l]] == stamp) continue;
          seen[u[l]] = stamp;
          const float* row = q.row(to, u[l]);
          for (std::size_t o = 0; o < n; o += 16) __builtin_prefetch(row + o);
        }
      }
    }
    const std::size_t a = steps[i].action;
    const float alpha = static_cast<float>(1 - alphaSlope * static_cast<double>(from + i));
    const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(steps[i].cell) << d];
    for (int j = 0; j < corners; ++j) {
      const std::size_t v = corner[j];
      float target;
      if constexpr (kCompact) {
        GridTransition t = transition(i, corner, j);
        t.reward = g.reward[a * g.vertexCount + v];
        target = backup(q, g, a, t);
      } else {
        target = backup(q, g, a, transition(i, corner, j));
      }
      float& value = q.at(a, v);
      value += alpha * (target - value);
    }
  }
  stamp_ = stamp;
}

void QLearningUpdate::update(const std::vector<WalkStep>& steps, const std::vector<GridTransition>& landed,
                             std::uint64_t from) {
  if (g_.compact())
    update<true>(steps, landed, from);
  else
    update<false>(steps, landed, from);
}

}  // namespace mgrl::learners
