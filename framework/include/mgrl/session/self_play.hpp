#pragma once
/// \file
/// Self-play rounds of training (trainScenario, training.hpp): how a round's table does against the
/// opponent it was trained against, and how much it gains over the previous round's.
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// The best-response gap on the grid: in the problem a round was trained in (its
/// opponent playing `opponent`'s table), the mean over every graph state and grid vertex of
/// the round's table's value (value iteration's optimum there) minus the value of playing
/// greedily on `opponent`'s table (policy evaluation in the same problem,
/// evaluateGreedy()). `table` must be the problem's optimum (a converged value
/// iteration). At least 0 up to the tolerances, and free of the episodes' sampling
/// and of the grid's interpolation error in continuous play; 0 when the opponent's table is
/// already its own best answer, so it shrinks as the rounds settle.
struct TableGap {
  double gap = 0;
  double seconds = 0;  ///< the policy evaluation's time
  int sweeps = 0;
  bool converged = true;  ///< false: the evaluation stopped at its sweep limit
};
TableGap bestResponseGapOnGrid(const GridModel& grid, const StateActionModel& model, const QTable& table,
                               const QTable& opponent, unsigned threads);

/// Round `round`'s entry for train's report and the bundle's record: {"round", "opponent",
/// "return"} and, given the table the opponent plays (the previous round's, or with
/// `against: average` the earlier rounds' mean), {"previous_return", "gap"}: the mean
/// discounted return of each table's greedy policy against the behaviour's environment as
/// it stands (its opponent playing that table), over the same 200 episodes of 10 s, and
/// their difference, which the grid's interpolation and the episodes' sampling can make
/// negative; with `tableGap` also {"table_gap"}, the exact gap on the grid
/// (bestResponseGapOnGrid), which shrinks as the rounds settle. Against a learned opponent
/// also {"landed_per_min", "taken_per_min"} and the opponent table's
/// {"previous_landed_per_min", "previous_taken_per_min"}: the fist punches landing within
/// 0.16 m of either head (the world's fist and head radii) in those episodes, as the model
/// plays them. Says the figures through `log`, one line a round.
nlohmann::json selfPlayRound(const Behavior& behavior, const StateActionModel& model, int round, const QTable& table,
                             const QTable* previous, const std::optional<TableGap>& tableGap,
                             const std::function<void(const std::string&)>& log);

/// What train adds to a round's line after the episodes' difference: "" for one of at
/// least 0; for a negative one, with `optimum` (the round's table is the grid problem's
/// optimum, a converged value iteration), that the grid's best response is not the best
/// where the episodes move between vertices and that a finer grid narrows this; without,
/// only that the round's table does worse in those episodes.
std::string gapNote(double gap, bool optimum);

/// `against: average`: the mean of rounds 1..n's tables, from the mean of rounds 1..n - 1's
/// (null for n = 1) and round n's table: mean + (table - mean) / n, entry by entry. Throws
/// mgrl::Error when the tables differ in layout (an adaptive grid refines each round
/// differently).
std::shared_ptr<const QTable> meanOfRounds(const QTable* mean, const QTable& table, int n);

}  // namespace mgrl
