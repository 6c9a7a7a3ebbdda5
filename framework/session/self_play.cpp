#include "mgrl/session/self_play.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/learning/policy_evaluation.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/session/graph_source.hpp"

namespace mgrl {

namespace {

// The same episodes for every table compared.
constexpr std::uint64_t kSelfPlaySeed = 43;
constexpr int kEpisodes = 200;
constexpr double kSeconds = 10;
// A punch lands, in the exchange counts, with its fist tip this close to the head: the
// world's fist and head radii (0.05 + 0.11 m).
constexpr double kLandRadius = 0.16;
// At most this many sweeps of the gap's policy evaluation (spar_learned: 16).
constexpr int kGapSweeps = 2000;

// How one table's greedy policy does over the episodes.
struct Play {
  double meanReturn = 0;
  double landedPerMinute = 0, takenPerMinute = 0;  ///< punches on the heads, both ways
};

// The greedy policy of `table` over 200 episodes of 10 s against the behaviour's
// environment as it stands: starts drawn from `seed` (graph state uniform, the opponent at a
// grid position drawn uniformly in grid coordinates, its own state drawn by the
// environment); its mean discounted return and, against a learned opponent, the fist
// punches landing on either head, frame by frame as the model plays them. Not eval's
// Trials: those end a trial at its first success, and a round is measured over the whole
// episode.
Play play(const Behavior& b, const StateActionModel& m, const QTable& table, std::uint64_t seed) {
  Rng rng(seed);
  const double gamma = b.reward->gamma();
  const double limit = kSeconds / m.frameTime;
  const int head = headJoint(m);
  const TrackedOpponent* opponent = b.environment->as<TrackedOpponent>();
  const bool exchanges = head >= 0 && opponent;
  std::vector<OpponentFrame> track;
  double total = 0, landed = 0, taken = 0;
  for (int episode = 0; episode < kEpisodes; ++episode) {
    auto s = static_cast<std::uint32_t>(rng.below(m.stateCount()));
    TargetState e = b.environment->draw(b.discretizer->sample(rng).position, rng);
    double elapsed = 0, discount = 1, sum = 0;
    while (elapsed < limit) {
      const std::size_t a = greedyAction(m, *b.discretizer, table, s, e);
      sum += discount * b.reward->evaluate(m, a, e);
      if (exchanges) {
        opponent->track(m, a, e, track);
        for (std::uint32_t t = 1; t <= track.size(); ++t) {
          const OpponentFrame& o = track[t - 1];
          const Eigen::Vector3d target = opponentTarget(m, o, head, e.position.y());
          landed += strikeAt(m, a, t, kFists, kLandRadius, false, target) > 0;
          taken += trackedStrikeAt(m, m.actionFrameBegin[a] + t - 1, head, o, kFists, kLandRadius, false) > 0;
        }
      }
      const auto frames = static_cast<double>(m.actionLength(a));
      discount *= std::pow(gamma, frames);
      elapsed += frames;
      e = b.environment->next(m, a, e);
      s = m.actionTo[a];
    }
    total += sum;
  }
  const double minutes = kEpisodes * kSeconds / 60;
  return {total / kEpisodes, landed / minutes, taken / minutes};
}

// ", landing 1.2 and taking 0.8 punches a minute" (nothing without a learned opponent).
std::string exchangeText(const Play& p) {
  if (p.landedPerMinute == 0 && p.takenPerMinute == 0) return "";
  return fmt::format(" (landing {:.2f} and taking {:.2f} punches a minute)", p.landedPerMinute, p.takenPerMinute);
}

}  // namespace

std::string gapNote(double gap, bool optimum) {
  if (!(gap < 0)) return "";
  if (!optimum) return " (negative: this round's table does worse in these episodes than the one it answers)";
  return " (negative: the grid's best response is not the best where the episodes move between its vertices; a "
         "finer grid narrows this, scenarios/README.md)";
}

TableGap bestResponseGapOnGrid(const GridModel& grid, const StateActionModel& model, const QTable& table,
                               const QTable& opponent, unsigned threads) {
  const auto start = std::chrono::steady_clock::now();
  // Until no value changes by a hundredth of a reward unit (the gaps measured are tenths and
  // more), from the round's own values, which differ from Q^pi by the gap: a third of the
  // sweeps from 0. The iterates come down to Q^pi from above, so what is left (at most
  // gamma_a / (1 - gamma_a) hundredths) makes the gap a little low, never high.
  const PolicyValues own = evaluateGreedy(opponent, grid, model, threads, 0.01, kGapSweeps, &table);
  TableGap out;
  out.converged = own.change < 0.01;
  out.gap = meanAdvantageOver(table, own.q, opponent);
  out.sweeps = own.sweeps;
  out.seconds = since(start);
  return out;
}

nlohmann::json selfPlayRound(const Behavior& behavior, const StateActionModel& model, int round, const QTable& table,
                             const QTable* previous, const std::optional<TableGap>& tableGap,
                             const std::function<void(const std::string&)>& log) {
  // What the opponent plays ("" for a model without a policy to play).
  const SelfPlayOpponent* selfPlay = behavior.environment->as<SelfPlayOpponent>();
  const std::string against = selfPlay ? selfPlay->policyKey() : std::string();
  nlohmann::json entry = {{"round", round}, {"opponent", against}};
  const Play me = play(behavior, model, table, kSelfPlaySeed);
  const double mine = me.meanReturn;
  entry["return"] = mine;
  entry["landed_per_min"] = me.landedPerMinute;
  entry["taken_per_min"] = me.takenPerMinute;
  if (!previous) {
    log(fmt::format("train {}: round {}: return {:.3f}{} against its {} opponent", behavior.name, round, mine,
                    exchangeText(me), against));
    return entry;
  }
  const Play them = play(behavior, model, *previous, kSelfPlaySeed);
  const double old = them.meanReturn;
  entry["previous_return"] = old;
  entry["previous_landed_per_min"] = them.landedPerMinute;
  entry["previous_taken_per_min"] = them.takenPerMinute;
  entry["gap"] = mine - old;
  const std::string episodes =
      fmt::format("in 200 episodes of 10 s it returns {:.3f}{}, the opponent's own table {:.3f}{}: {:+.3f}{}", mine,
                  exchangeText(me), old, exchangeText(them), mine - old, gapNote(mine - old, tableGap.has_value()));
  if (tableGap) {
    entry["table_gap"] = tableGap->gap;
    log(
        fmt::format("train {}: round {}: best-response gap {:.3f} on the grid against {}'s table (its value less that "
                    "of the opponent's own table played greedily, by policy evaluation: {} sweeps in {:.1f} s{}); {}",
                    behavior.name, round, tableGap->gap, against, tableGap->sweeps, tableGap->seconds,
                    tableGap->converged ? "" : ", not converged: an estimate", episodes));
  } else {
    log(fmt::format("train {}: round {}: against {}'s table {}", behavior.name, round, against, episodes));
  }
  return entry;
}

std::shared_ptr<const QTable> meanOfRounds(const QTable* mean, const QTable& table, int n) {
  if (!mean) return std::make_shared<const QTable>(table);
  if (mean->actionCount() != table.actionCount() || mean->vertexCount() != table.vertexCount())
    throw Error(
        fmt::format("self-play against: average: round {}'s table has {} actions x {} vertices, the earlier "
                    "rounds' {} x {} (an adaptive grid refines each round differently; use against: previous)",
                    n, table.actionCount(), table.vertexCount(), mean->actionCount(), mean->vertexCount()));
  auto next = std::make_shared<QTable>(*mean);
  const std::span<float> out = next->values();
  const std::span<const float> in = table.values();
  const float weight = 1.0F / static_cast<float>(n);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] += (in[i] - out[i]) * weight;
  return next;
}

}  // namespace mgrl
