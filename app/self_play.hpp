#pragma once
/// \file
/// Self-play rounds of `mgrl train` (issue 43): how a round's table does against the
/// opponent it was trained against, and how much it gains over the previous round's.
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl::app {

/// Round `round`'s entry for train's report and the bundle's record: {"round", "opponent",
/// "return"} and, given the previous round's table, {"previous_return", "gap"}: the mean
/// discounted return of each table's greedy policy against the behaviour's environment as
/// it stands (its opponent playing the previous round's table), over the same 200 episodes
/// of 10 s; the gap (this minus the previous) is the best-response gap, which shrinks as the
/// rounds settle. Says the figures through `log`.
nlohmann::json selfPlayRound(const Behavior& behavior, const StateActionModel& model, int round, const QTable& table,
                             const QTable* previous, const std::function<void(const std::string&)>& log);

}  // namespace mgrl::app
