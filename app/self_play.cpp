#include "self_play.hpp"

#include <cmath>
#include <cstdint>
#include <memory>
#include <span>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/learning/problem.hpp"

namespace mgrl::app {

namespace {

// The same episodes for every table compared.
constexpr std::uint64_t kSelfPlaySeed = 43;

// The mean discounted return of the greedy policy of `table` over 200 episodes of 10 s
// against the behaviour's environment as it stands: starts drawn from `seed` (graph state
// uniform, the opponent at a grid position drawn uniformly in grid coordinates, its own
// state drawn by the environment). Not eval's Trials: those end a trial at its first
// success, and a round's return is measured over the whole episode.
double meanReturn(const Behavior& b, const StateActionModel& m, const QTable& table, std::uint64_t seed) {
  constexpr int kEpisodes = 200;
  constexpr double kSeconds = 10;
  Rng rng(seed);
  const double gamma = b.reward->gamma();
  const double limit = kSeconds / m.frameTime;
  double total = 0;
  for (int episode = 0; episode < kEpisodes; ++episode) {
    auto s = static_cast<std::uint32_t>(rng.below(m.stateCount()));
    TargetState e = b.environment->draw(b.discretizer->sample(rng).position, rng);
    double elapsed = 0, discount = 1, sum = 0;
    while (elapsed < limit) {
      const std::size_t a = greedyAction(m, *b.discretizer, table, s, e);
      sum += discount * b.reward->evaluate(m, a, e);
      const auto frames = static_cast<double>(m.actionLength(a));
      discount *= std::pow(gamma, frames);
      elapsed += frames;
      e = b.environment->next(m, a, e);
      s = m.actionTo[a];
    }
    total += sum;
  }
  return total / kEpisodes;
}

}  // namespace

std::string gapNote(double gap) {
  if (!(gap < 0)) return "";
  return " (negative: on this grid the best response's table does worse in continuous play than the "
         "opponent's own; a finer grid narrows this, scenarios/README.md)";
}

nlohmann::json selfPlayRound(const Behavior& behavior, const StateActionModel& model, int round, const QTable& table,
                             const QTable* previous, const std::function<void(const std::string&)>& log) {
  nlohmann::json entry = {{"round", round}, {"opponent", behavior.environment->policyKey()}};
  const double mine = meanReturn(behavior, model, table, kSelfPlaySeed);
  entry["return"] = mine;
  if (!previous) {
    log(fmt::format("train {}: round {}: return {:.3f} against its {} opponent", behavior.name, round, mine,
                    behavior.environment->policyKey()));
    return entry;
  }
  const double old = meanReturn(behavior, model, *previous, kSelfPlaySeed);
  entry["previous_return"] = old;
  entry["gap"] = mine - old;
  log(
      fmt::format("train {}: round {}: return {:.3f} against {}'s table, which itself gets {:.3f}: "
                  "best-response gap {:.3f}{}",
                  behavior.name, round, mine, behavior.environment->policyKey(), old, mine - old, gapNote(mine - old)));
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

}  // namespace mgrl::app
