#include "mgrl/controller.hpp"

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
