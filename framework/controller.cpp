#include "mgrl/controller.hpp"

namespace mgrl {

PolicyController::PolicyController(const StateActionModel& model, std::vector<PolicyPart> parts)
    : model_(model), parts_(std::move(parts)) {}

std::size_t PolicyController::choose(std::uint32_t s, const Eigen::Vector3d& e) {
  const std::uint32_t begin = model_.stateActionBegin[s];
  const std::uint32_t n = model_.stateActionBegin[s + 1] - begin;
  scores_.assign(n, 0.0f);
  for (const PolicyPart& part : parts_) {
    GridCell cell;
    if (part.activation == Activation::TargetInside) {
      if (!part.grid->locate(e, cell)) continue;
    } else {
      cell = part.grid->locateClamped(e);
    }
    const Stencil stencil = part.grid->stencil(cell);
    for (int k = 0; k < stencil.size; ++k) {
      const float w = static_cast<float>(part.weight) * stencil.weight[k];
      const float* row = part.table->row(s, stencil.vertex[k]);
      for (std::uint32_t j = 0; j < n; ++j) scores_[j] += w * row[j];
    }
  }
  std::uint32_t best = 0;
  for (std::uint32_t j = 1; j < n; ++j)
    if (scores_[j] > scores_[best]) best = j;
  return begin + best;
}

}  // namespace mgrl
