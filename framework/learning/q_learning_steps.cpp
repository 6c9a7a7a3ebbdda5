// The paper's Q-learning (sec. 4.2) one action at a time; see q_learning_steps.hpp. The
// walk consumes random numbers in learners/q_learning_walk.cpp's order and the update is the same
// expression, so the same seed and budget give the same table (tests/learning_test.cpp).
#include "mgrl/learning/q_learning_steps.hpp"

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

QLearningSteps::QLearningSteps(const Problem& problem, std::uint64_t budget, std::uint64_t seed, double alphaFinal)
    : problem_(problem),
      frame_(GridModel::frame(problem)),
      budget_(budget),
      alphaSlope_((1 - alphaFinal) / static_cast<double>(budget)),
      rng_(seed) {
  if (budget == 0) throw Error("q_learning steps: expected a budget of at least 1 action, found 0");
  if (!frame_.hanging.empty())
    throw Error(
        fmt::format("q_learning steps: the {} grid has {} hanging vertices, which Q-learning's updates "
                    "cannot keep continuous",
                    problem.grid.type(), frame_.hanging.size()));
  table_ = QTable(problem.model, frame_.vertexCount);
  seen_.assign(frame_.vertexCount * frame_.actionCount, 0);
  vertex_.resize(frame_.vertexCount);
  for (std::size_t v = 0; v < frame_.vertexCount; ++v) vertex_[v] = problem.grid.vertexState(v);
  restart();
}

double QLearningSteps::tableBytes(const Problem& problem) {
  // The table, the touched flags and the vertex positions.
  const double pairs =
      static_cast<double>(problem.model.actionCount()) * static_cast<double>(problem.grid.vertexCount());
  return pairs * (sizeof(float) + 1) + static_cast<double>(problem.grid.vertexCount()) * sizeof(TargetState);
}

// As QLearningWalk::restart() (learners/q_learning_walk.cpp): a random pose, then a random target
// inside the grid.
void QLearningSteps::restart() {
  state_ = static_cast<std::uint32_t>(rng_.below(problem_.model.stateCount()));
  do target_ = problem_.grid.sample(rng_);
  while (!problem_.grid.inside(target_));
  ++restarts_;
}

QStep QLearningSteps::step() {
  if (done()) throw Error(fmt::format("q_learning steps: the budget of {} actions is spent", budget_));
  const StateActionModel& m = problem_.model;
  const Discretizer& grid = problem_.grid;
  const GridModel& g = frame_;
  GridCell cell;
  if (!grid.locate(target_, cell)) {  // only on the boundary's round-off, as in q_learning
    restart();
    grid.locate(target_, cell);
  }
  QStep out;
  out.update = updates_ + 1;
  out.state = state_;
  out.target = target_.position;
  const std::uint32_t begin = m.stateActionBegin[state_], end = m.stateActionBegin[state_ + 1];
  const std::size_t a = begin + static_cast<std::uint32_t>(rng_.below(end - begin));
  out.action = static_cast<std::uint32_t>(a);
  out.frames = static_cast<std::uint32_t>(m.actionLength(a));
  // The paper's update of every vertex next to e (sec. 4.2, Fig. 4):
  //   Q(v, a) += alpha (r(v, a) + gamma^t max_a' Q(e'_v, a') - Q(v, a)).
  const float alpha = static_cast<float>(1 - alphaSlope_ * static_cast<double>(updates_));
  out.alpha = alpha;
  const Stencil stencil = grid.stencil(cell);
  const int corners = 1 << g.dimension;
  const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(cell.cell) << g.dimension];
  for (int j = 0; j < corners; ++j) {
    const std::size_t v = corner[j];
    const GridTransition t = tabulate(problem_, a, vertex_[v]);
    QStepVertex row;
    row.vertex = static_cast<std::uint32_t>(v);
    row.position = vertex_[v].position;
    for (int k = 0; k < stencil.size; ++k)
      if (stencil.vertex[k] == v) row.weight += stencil.weight[k];
    row.reward = t.reward;
    row.discount = g.discount[a];
    row.nextInside = t.cell >= 0;
    row.next = problem_.environment.next(m, a, vertex_[v]).position;
    row.future =
        t.cell >= 0 ? maxInterpolated(table_, g, g.actionTo[a], static_cast<std::uint32_t>(t.cell), t.frac) : 0;
    const float target = backup(table_, g, a, t);
    row.backup = target;
    float& value = table_.at(a, v);
    row.before = value;
    value += alpha * (target - value);
    row.after = value;
    std::uint8_t& seen = seen_[a * g.vertexCount + v];
    touched_ += seen == 0;
    seen = 1;
    out.vertices.push_back(row);
  }
  target_ = g.rigid.empty() ? problem_.environment.next(m, a, target_) : g.rigidNext(a, target_);
  state_ = m.actionTo[a];
  out.targetNext = target_.position;
  out.nextState = state_;
  ++updates_;
  // The paper restarts when the target leaves the grid.
  if (!grid.inside(target_)) {
    restart();
    out.restarted = true;
  }
  return out;
}

}  // namespace mgrl
