#include "mgrl/learning/q_table.hpp"

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

QTable::QTable(const StateActionModel& model, std::size_t vertexCount)
    : vertexCount_(vertexCount), stateBegin_(model.stateActionBegin) {
  const std::size_t actions = model.actionCount();
  actionBase_.resize(actions);
  actionStride_.resize(actions);
  for (std::size_t s = 0; s + 1 < stateBegin_.size(); ++s) {
    const std::uint32_t n = stateBegin_[s + 1] - stateBegin_[s];
    for (std::uint32_t j = 0; j < n; ++j) {
      const std::size_t a = stateBegin_[s] + j;
      actionBase_[a] = static_cast<std::uint64_t>(vertexCount) * stateBegin_[s] + j;
      actionStride_[a] = n;
    }
  }
  size_ = actions * vertexCount;
  values_.assign(size_ + kPadding, 0.0f);
}

std::vector<float> QTable::actionMajor() const {
  std::vector<float> out(size_);
  for (std::size_t a = 0; a < actionCount(); ++a)
    for (std::size_t v = 0; v < vertexCount_; ++v) out[a * vertexCount_ + v] = values_[index(a, v)];
  return out;
}

void QTable::setActionMajor(std::span<const float> values) {
  if (values.size() != size_)
    throw Error(fmt::format("Q table: expected {} values ({} actions x {} vertices), found {}", size_,
                            actionCount(), vertexCount_, values.size()));
  for (std::size_t a = 0; a < actionCount(); ++a)
    for (std::size_t v = 0; v < vertexCount_; ++v) values_[index(a, v)] = values[a * vertexCount_ + v];
}

}  // namespace mgrl
