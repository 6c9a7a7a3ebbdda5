#include "mgrl/controller.hpp"

#include <cmath>
#include <limits>

#include "mgrl/problem.hpp"

namespace mgrl {

PolicyController::PolicyController(const StateActionModel& model, std::vector<PolicyPart> parts)
    : model_(model), parts_(std::move(parts)) {}

std::size_t PolicyController::choose(std::uint32_t s, const Eigen::Vector3d& e) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  const std::uint32_t n = model_.stateActionBegin[s + 1] - begin;
  buffer_.assign(n + 16, 0.0f);  // vector code writes whole 16-float registers
  count_ = n;
  for (const PolicyPart& part : parts_) {
    GridCell cell;
    if (part.activation == Activation::TargetInside) {
      if (!part.grid->locate(e, cell)) continue;
    } else {
      cell = part.grid->locateClamped(e);
    }
    addInterpolated(buffer_.data(), *part.table, s, part.grid->stencil(cell), static_cast<float>(part.weight));
  }
  std::uint32_t best = 0;
  for (std::uint32_t j = 1; j < n; ++j)
    if (buffer_[j] > buffer_[best]) best = j;
  return begin + best;
}

}  // namespace mgrl

namespace mgrl {

OnlineSearchController::OnlineSearchController(const StateActionModel& model, const EnvironmentModel& environment,
                                               std::vector<SearchPart> parts, int horizon, double gamma)
    : model_(model), environment_(environment), parts_(std::move(parts)), horizon_(horizon) {
  discount_.resize(model.actionCount());
  for (std::size_t a = 0; a < model.actionCount(); ++a)
    discount_[a] = std::pow(gamma, static_cast<double>(model.actionLength(a)));
}

double OnlineSearchController::reward(std::size_t a, const Eigen::Vector3d& e) const {
  double r = 0;
  for (const SearchPart& part : parts_) {
    if (part.activation == Activation::TargetInside && !part.grid->inside(e)) continue;
    r += part.weight * part.reward->evaluate(model_, a, e);
  }
  return r;
}

double OnlineSearchController::value(std::uint32_t s, const Eigen::Vector3d& e, int depth) {
  if (depth == 0) return 0;
  double best = -std::numeric_limits<double>::infinity();
  for (std::uint32_t a = model_.stateActionBegin[s]; a < model_.stateActionBegin[s + 1]; ++a) {
    ++expanded_;
    const double q = reward(a, e) + discount_[a] * value(model_.actionTo[a], environment_.next(model_, a, e), depth - 1);
    best = std::max(best, q);
  }
  return best;
}

std::size_t OnlineSearchController::choose(std::uint32_t s, const Eigen::Vector3d& e) {
  expanded_ = 0;
  std::size_t bestAction = model_.stateActionBegin[s];
  double best = -std::numeric_limits<double>::infinity();
  for (std::uint32_t a = model_.stateActionBegin[s]; a < model_.stateActionBegin[s + 1]; ++a) {
    ++expanded_;
    const double q = reward(a, e) + discount_[a] * value(model_.actionTo[a], environment_.next(model_, a, e), horizon_ - 1);
    if (q > best) {
      best = q;
      bestAction = a;
    }
  }
  return bestAction;
}

}  // namespace mgrl
