#include "mgrl/runtime/controller.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/learning/problem.hpp"

namespace mgrl {

std::size_t RandomController::choose(std::uint32_t s, const TargetState&, Rng& rng) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  return begin + rng.below(model_.stateActionBegin[s + 1] - begin);
}

std::size_t RandomController::choose(std::uint32_t s, const TargetState&, Rng& rng, std::span<const std::uint8_t> allowed) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  const auto count = static_cast<std::uint32_t>(std::count_if(allowed.begin(), allowed.end(), [](std::uint8_t x) { return x != 0; }));
  if (count == 0) throw Error(fmt::format("controller: expected an allowed action at state {}, found none", s));
  std::uint32_t draw = static_cast<std::uint32_t>(rng.below(count));
  for (std::uint32_t j = 0;; ++j)
    if (allowed[j] != 0 && draw-- == 0) return begin + j;
}

PursueController::PursueController(const StateActionModel& model, double stopDistance, bool stand)
    : model_(model), stopDistance_(stopDistance), stand_(stand) {
  if (!(stopDistance >= 0 && std::isfinite(stopDistance)))
    throw Error(fmt::format("pursue controller: expected a stop distance of at least 0 m, found {}", stopDistance));
}

double PursueController::punchScore(std::span<const ActionHit> hits, const Eigen::Vector3d& aim) {
  double punch = 0;
  for (const ActionHit& h : hits)
    punch = std::max(punch, 1 - std::min(1.0, (Eigen::Vector3d(h.x, h.y, h.z) - aim).norm() / kPunchReach));
  return punch;
}

std::size_t PursueController::choose(std::uint32_t s, const TargetState& e, Rng& rng) {
  thread_local std::vector<std::uint8_t> all;
  all.assign(model_.stateActionBegin[s + 1] - model_.stateActionBegin[s], 1);
  return choose(s, e, rng, all);
}

std::size_t PursueController::choose(std::uint32_t s, const TargetState& e, Rng&,
                                     std::span<const std::uint8_t> allowed) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  const std::uint32_t n = model_.stateActionBegin[s + 1] - begin;
  std::int64_t best = -1;
  double bestCost = std::numeric_limits<double>::infinity();
  for (std::uint32_t j = 0; j < n; ++j) {
    if (allowed[j] == 0) continue;
    const std::size_t a = begin + j;
    const GroundMotion d = model_.displacement(a);
    const Eigen::Vector3d q = inverseTransformPoint(d, e.position);  // from the action's end
    const double facing = std::abs(std::atan2(q.x(), q.z()));
    // Standing: as near where it is as the graph allows (eval's trials: near its start).
    const double place = stand_ ? std::hypot(d.dx, d.dz) : std::abs(std::hypot(q.x(), q.z()) - stopDistance_);
    if (const double cost = place + kTurnCost * facing - kPunchWeight * punchScore(model_.hitsOf(a), e.position);
        cost < bestCost) {
      bestCost = cost;
      best = static_cast<std::int64_t>(a);
    }
  }
  if (best < 0) throw Error(fmt::format("controller: expected an allowed action at state {}, found none", s));
  return static_cast<std::size_t>(best);
}

PolicyController::PolicyController(const StateActionModel& model, std::vector<PolicyPart> parts, Variety variety)
    : model_(model), parts_(std::move(parts)), variety_(variety) {
  variety_.topK = std::max(1, variety_.topK);
}

void PolicyController::score(std::uint32_t s, const TargetState& e) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  const std::uint32_t n = model_.stateActionBegin[s + 1] - begin;
  buffer_.assign(n + 16, 0.0f);  // vector code writes whole 16-float registers
  count_ = n;
  for (const PolicyPart& part : parts_) {
    if (!stanceActive(part.stance, e.stance)) continue;
    GridCell cell;
    if (part.activation == Activation::TargetInside) {
      if (!part.grid->locate(e, cell)) continue;
    } else {
      cell = part.grid->locateClamped(e);
    }
    addInterpolated(buffer_.data(), *part.table, s, part.grid->stencil(cell), static_cast<float>(part.weight));
  }
}

std::size_t PolicyController::choose(std::uint32_t s, const TargetState& e) {
  score(s, e);
  const std::uint32_t begin = model_.stateActionBegin[s];
  const auto n = static_cast<std::uint32_t>(count_);
  std::uint32_t best = 0;
  for (std::uint32_t j = 1; j < n; ++j)
    if (buffer_[j] > buffer_[best]) best = j;
  return begin + best;
}

std::size_t PolicyController::choose(std::uint32_t s, const TargetState& e, Rng& rng) {
  if (variety_.topK == 1) return choose(s, e);
  score(s, e);
  return pick(s, rng, {});
}

std::size_t PolicyController::choose(std::uint32_t s, const TargetState& e, Rng& rng,
                                     std::span<const std::uint8_t> allowed) {
  score(s, e);
  return pick(s, rng, allowed);
}

// The top k of the scored actions (all of them when `allowed` is empty), ties by index
// (a stable, seed-independent order), less those below the margin; one drawn with rng.
std::size_t PolicyController::pick(std::uint32_t s, Rng& rng, std::span<const std::uint8_t> allowed) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  const auto n = static_cast<std::uint32_t>(count_);
  ranked_.clear();
  for (std::uint32_t j = 0; j < n; ++j)
    if (allowed.empty() || allowed[j] != 0) ranked_.push_back(j);
  if (ranked_.empty()) throw Error(fmt::format("controller: expected an allowed action at state {}, found none", s));
  const auto k = std::min<std::uint32_t>(static_cast<std::uint32_t>(ranked_.size()), static_cast<std::uint32_t>(variety_.topK));
  std::partial_sort(ranked_.begin(), ranked_.begin() + k, ranked_.end(), [&](std::uint32_t a, std::uint32_t b) {
    return buffer_[a] > buffer_[b] || (buffer_[a] == buffer_[b] && a < b);
  });
  std::uint32_t candidates = k;
  if (variety_.margin > 0) {
    const double best = buffer_[ranked_[0]];
    const double floor = best - variety_.margin * std::abs(best);
    candidates = 1;
    while (candidates < k && buffer_[ranked_[candidates]] >= floor) ++candidates;
  }
  return begin + ranked_[candidates == 1 ? 0 : rng.below(candidates)];
}

}  // namespace mgrl

namespace mgrl {

OnlineSearchController::OnlineSearchController(const StateActionModel& model, const EnvironmentModel& environment,
                                               std::vector<SearchPart> parts, int horizon, double gamma)
    : OnlineSearchController(model, environment, std::move(parts), SearchHorizon{horizon, 0}, gamma) {}

OnlineSearchController::OnlineSearchController(const StateActionModel& model, const EnvironmentModel& environment,
                                               std::vector<SearchPart> parts, SearchHorizon horizon, double gamma)
    : model_(model),
      environment_(environment),
      parts_(std::move(parts)),
      horizon_(std::max(1, horizon.actions)),
      horizonFrames_(horizon.seconds > 0 ? horizon.seconds / model.frameTime
                                         : std::numeric_limits<double>::infinity()) {
  discount_.resize(model.actionCount());
  for (std::size_t a = 0; a < model.actionCount(); ++a)
    discount_[a] = std::pow(gamma, static_cast<double>(model.actionLength(a)));
}

double OnlineSearchController::reward(std::size_t a, const TargetState& e) const {
  double r = 0;
  for (const SearchPart& part : parts_) {
    if (!stanceActive(part.stance, e.stance)) continue;
    if (part.activation == Activation::TargetInside && !part.grid->inside(e)) continue;
    r += part.weight * part.reward->evaluate(model_, a, e);
  }
  return r;
}

double OnlineSearchController::backup(std::size_t a, const TargetState& e, int depth, double frames) {
  ++expanded_;
  return reward(a, e) + discount_[a] * value(model_.actionTo[a], nextHoldingStance(environment_, model_, a, e),
                                             depth - 1, frames - static_cast<double>(model_.actionLength(a)));
}

double OnlineSearchController::value(std::uint32_t s, const TargetState& e, int depth, double frames) {
  if (depth == 0 || frames <= 0) return 0;
  double best = -std::numeric_limits<double>::infinity();
  for (std::uint32_t a = model_.stateActionBegin[s]; a < model_.stateActionBegin[s + 1]; ++a)
    best = std::max(best, backup(a, e, depth, frames));
  return best;
}

std::size_t OnlineSearchController::bestFirstAction(std::uint32_t s, const TargetState& e,
                                                    std::span<const std::uint8_t> allowed) {
  expanded_ = 0;
  const std::uint32_t begin = model_.stateActionBegin[s];
  std::size_t bestAction = model_.actionCount();
  double best = -std::numeric_limits<double>::infinity();
  for (std::uint32_t a = begin; a < model_.stateActionBegin[s + 1]; ++a) {
    if (!allowed.empty() && allowed[a - begin] == 0) continue;
    const double q = backup(a, e, horizon_, horizonFrames_);
    if (bestAction == model_.actionCount() || q > best) {
      best = q;
      bestAction = a;
    }
  }
  if (bestAction == model_.actionCount())
    throw Error(fmt::format("controller: expected an allowed action at state {}, found none", s));
  return bestAction;
}

std::size_t OnlineSearchController::choose(std::uint32_t s, const TargetState& e) { return bestFirstAction(s, e, {}); }

std::size_t OnlineSearchController::choose(std::uint32_t s, const TargetState& e, Rng&,
                                           std::span<const std::uint8_t> allowed) {
  return bestFirstAction(s, e, allowed);
}

}  // namespace mgrl
