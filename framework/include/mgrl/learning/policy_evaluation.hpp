#pragma once
/// \file
/// Policy evaluation on a tabulated problem (the exact best-response gap of self-play rounds): the
/// values of a fixed greedy policy in the same grid MDP that value iteration solves, so that
/// a self-play round's table and the table its opponent plays are compared where both were
/// made, without the sampling noise and the grid's interpolation error of episodes.
#include <cstddef>

#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// The action-values Q^pi of the policy that plays greedily on `policy` from the next
/// decision on, in the problem `g` tabulates: Q^pi(v, a) = r(v, a) + gamma^t_a
/// Q^pi(e'(v, a), pi(e')), where pi(e') is the out-action of a's end state with the largest
/// `policy` value interpolated at e' (ties to the lowest index; value iteration's backup
/// takes the max there instead), and the future is 0 when e' leaves the grid. Jacobi
/// sweeps from `start` (Q = 0 if null; the closer to Q^pi, the fewer sweeps) until the
/// largest change is below `tolerance` or `maxSweeps` have run; with value iteration's table Q* of the same problem, Q*
/// >= Q^pi entry by entry (Sutton & Barto, sec. 4.1 and 4.3: the optimal backup dominates any fixed policy's).
/// Deterministic whatever the thread count. Needs a tabulated or compact model without
/// hanging vertices (a fixed grid): throws mgrl::Error otherwise, or when `policy`'s layout
/// is not `g`'s.
struct PolicyValues {
  QTable q;
  int sweeps = 0;
  double change = 0;  ///< the last sweep's largest change
};
PolicyValues evaluateGreedy(const QTable& policy, const GridModel& g, const StateActionModel& model, unsigned threads,
                            double tolerance, int maxSweeps = 2000, const QTable* start = nullptr);

/// How much `best` (value iteration's table of a problem) gains over playing greedily on
/// `policy` in the same problem (`values`, evaluateGreedy's Q^pi of it): the mean over every
/// graph state s and grid vertex v of max_a best(s, v, a) - values(s, v, pi(s, v)), pi(s, v)
/// the greedy action of `policy` at the vertex. At least 0 up to the tolerances.
double meanAdvantageOver(const QTable& best, const QTable& values, const QTable& policy);

}  // namespace mgrl
