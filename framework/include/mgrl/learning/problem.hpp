#pragma once
/// \file
/// A learning problem (DESIGN.md sec. 2, "learn"): the state-action model, a grid over the
/// target's position, a reward and an environment model. Because both learners back values
/// up at grid vertices only (paper sec. 4.2: "the update is applied at every grid point
/// next to e, moving e' along"), everything a backup needs besides Q is a function of
/// (action, vertex) alone; GridModel tabulates it once: the reward r(v, a) and where the
/// vertex lands after the action (its cell and fractions, or outside).
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mgrl/core/huge_pages.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/discretizer.hpp"
#include "mgrl/learning/environment_model.hpp"
#include "mgrl/learning/q_table.hpp"
#include "mgrl/learning/reward.hpp"

namespace mgrl {

struct Problem {
  const StateActionModel& model;
  const Discretizer& grid;
  const Reward& reward;
  const EnvironmentModel& environment;
};

/// What a backup of (action a, vertex v) needs besides Q, in one 20-byte record so that
/// a backup reads one cache line of it.
struct GridTransition {
  float reward = 0;           ///< r(v, a)
  std::int32_t cell = -1;     ///< cell of e'(v, a), -1 outside the grid
  float frac[3] = {0, 0, 0};  ///< fractions of e'(v, a) in that cell
};

/// The problem tabulated on the grid: for action a and vertex v at index a * V + v.
struct GridModel {
  std::size_t vertexCount = 0, actionCount = 0;
  int dimension = 0;
  std::vector<std::uint32_t> corners;  ///< the grid's cell corner table
  /// The grid's hanging vertices (Discretizer::hanging()): sweep() sets their values from
  /// their sources' after every backup, and bellmanResidual() skips them.
  HangingVertices hanging;
  std::vector<GridTransition, HugePageAllocator<GridTransition>> transition;  ///< per (a, v); empty if compact
  /// A compact model (buildCompact(), for training at the memory limit) keeps only
  /// the rewards per (a, v), 4 bytes like Q itself instead of the 20 of a transition, and
  /// finds where a vertex lands when a backup asks (at()): the same arithmetic as
  /// tabulate(), so the same backups and the same tables, for a grid locate per backup.
  std::vector<float, HugePageAllocator<float>> reward;  ///< per (a, v), compact models only
  std::vector<TargetState> vertexState;                 ///< per vertex, compact models only
  std::vector<float> discount;                          ///< per action: gamma^(frames of a)
  /// Per action, if the environment model moves the target rigidly (it offers RigidTarget):
  /// (cos, sin, dx, dz) of the motion e' = R^T (e - d); else empty.
  std::vector<double> rigid;
  std::vector<std::uint32_t> actionTo;          ///< per action: its end state
  std::vector<std::uint32_t> stateActionBegin;  ///< the model's: actions by the state they leave
  /// Actions grouped by the state they end at: incoming[incomingBegin[s], incomingBegin[s+1]).
  std::vector<std::uint32_t> incomingBegin, incoming;

  std::size_t bytes() const;
  /// What training on `actions` x `vertices` needs at most (bytes), before anything is
  /// allocated: the model (tabulated: transitions; compact: rewards), the incoming lists
  /// and two Q tables (value iteration's Jacobi pair; Q-learning uses one).
  static double trainingBytes(std::size_t actions, std::size_t vertices, bool compact = false);

  bool compact() const { return transition.empty() && !reward.empty(); }
  /// What a backup of (action a, vertex v) needs besides Q: the stored record, or for a
  /// compact model the same record computed now.
  GridTransition at(std::size_t a, std::size_t v) const {
    return compact() ? landing(a, v) : transition[a * vertexCount + v];
  }
  /// A compact model's record of (a, v): its reward, and where v lands after a.
  GridTransition landing(std::size_t a, std::size_t v) const {
    GridTransition t = moved(a, v);
    t.reward = reward[a * vertexCount + v];
    return t;
  }
  /// Where vertex v lands after action a (cell, fractions) in a compact model; reward 0.
  GridTransition moved(std::size_t a, std::size_t v) const;

  /// The target after action a under a rigid environment model (`rigid` not empty): the
  /// same arithmetic as inverseTransformPoint(), from the precomputed sine and cosine.
  TargetState rigidNext(std::size_t a, const TargetState& state) const {
    const double* r = &rigid[4 * a];
    const Eigen::Vector3d& e = state.position;
    const double qx = e.x() - r[2], qz = e.z() - r[3];
    return Eigen::Vector3d(r[0] * qx - r[1] * qz, e.y(), r[1] * qx + r[0] * qz);
  }

  /// Tabulates `problem` on `threads` threads. The same inputs give the same bytes.
  /// `stop` (may be null) is checked every 64 actions: once set, throws TrainInterrupted.
  static GridModel build(const Problem& problem, unsigned threads, const std::atomic<bool>* stop = nullptr);
  /// The compact model of `problem` (see `reward`): tabulates the rewards only. It refers
  /// to the problem's grid, environment and state-action model, which must outlive it.
  static GridModel buildCompact(const Problem& problem, unsigned threads, const std::atomic<bool>* stop = nullptr);
  /// Everything build() makes except the per-(action, vertex) transitions: enough for maxInterpolated() and for
  /// stepping a walk (rigidNext) when the transitions a step needs are computed one by one with tabulate() (the
  /// viewer's learn panel, which takes a few steps of Q-learning where build() would tabulate them all), and for a
  /// learner that tabulates its own share (Learner::tabulatesItself()).
  static GridModel frame(const Problem& problem);

  // A compact model's problem, for landing().
  const Discretizer* landingGrid = nullptr;
  const EnvironmentModel* landingEnvironment = nullptr;
  const StateActionModel* landingModel = nullptr;
};

/// The transition record of action a from the grid vertex at `vertex`: what build() stores
/// at (a, v), the same bytes.
GridTransition tabulate(const Problem& problem, std::size_t a, const TargetState& vertex);

/// The 3-D record of where a state landed: its cell and fractions. On a layered grid a
/// backup's state must land exactly on its layer (layerFrac 0: the environment keeps the
/// speed); throws mgrl::Error if it does not.
void setLanding(GridTransition& t, const GridCell& cell);

/// max over s's out-actions a' of the Q(., a') interpolated at the point with cell
/// `cell` and fractions `frac` (the paper's "max_a' Q(e', a')").
float maxInterpolated(const QTable& q, const GridModel& g, std::uint32_t s, std::uint32_t cell, const float* frac);

/// sum[j] += scale * sum_k stencil.weight[k] Q(stencil.vertex[k], a_j) for s's out-actions
/// a_j. `sum` must have room for actionsOf(s) rounded up to 16 floats (vector code writes
/// whole registers; the extra entries receive garbage).
void addInterpolated(float* sum, const QTable& q, std::uint32_t s, const Stencil& stencil, float scale);

/// The greedy action at state s with the environment in state e: the largest of s's
/// out-actions' Q interpolated at e, clamped into the grid, ties to the lowest index (the
/// runtime's PolicyController::choose, for one table of weight 1).
std::size_t greedyAction(const StateActionModel& m, const Discretizer& grid, const QTable& q, std::uint32_t s,
                         const TargetState& e);

/// The backup of (action a, vertex v): r(v, a) + gamma^t_a max_a' Q(e'(v, a), a'), with
/// future value 0 when e' leaves the grid.
inline float backup(const QTable& q, const GridModel& g, std::size_t a, const GridTransition& t) {
  if (t.cell < 0) return t.reward;
  return t.reward + g.discount[a] * maxInterpolated(q, g, g.actionTo[a], static_cast<std::uint32_t>(t.cell), t.frac);
}
inline float backup(const QTable& q, const GridModel& g, std::size_t a, std::size_t v) {
  return backup(q, g, a, g.at(a, v));
}

/// One Jacobi sweep: out(v, a) = backup of `in` for every pair, in parallel over end
/// states (each reads one block of `in`, which stays in cache). Returns max |out - in|.
/// Hanging vertices (g.hanging) receive the interpolation of their sources' new values
/// instead of a backup. Deterministic whatever the thread count; a sweep over a subset of states is a function
/// of `in` alone (DESIGN.md sec. 8).
double sweep(const QTable& in, QTable& out, const GridModel& g, unsigned threads);
/// The same with a scratch buffer kept between sweeps (actions x vertices floats).
double sweep(const QTable& in, QTable& out, const GridModel& g, unsigned threads, std::vector<float>& stage);

/// The Bellman residual max over (v, a) of |backup(Q) - Q|, and its mean.
struct Residual {
  double max = 0, mean = 0;
};
/// With `stride` k > 1, over a fixed sample of one pair in k instead of every pair (for
/// action a, the (a mod k)-th of k runs of consecutive vertices: every action, and the
/// runs cover the grid; consecutive, so the sample reads k times less memory too), for
/// k times less work: the max is then a lower bound of the whole table's, the mean an
/// estimate of its mean. Deterministic whatever the thread count.
Residual bellmanResidual(const QTable& q, const GridModel& g, unsigned threads, std::size_t stride = 1);

}  // namespace mgrl
