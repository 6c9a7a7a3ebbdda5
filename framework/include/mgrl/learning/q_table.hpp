#pragma once
/// \file
/// Q values of one behaviour: conceptually one table per action over the grid's vertices
/// (paper sec. 4.2), Q(v, a). Stored state-major for the access pattern of every learner
/// and controller: at a state s the values of all of s's out-actions at vertex v are
/// contiguous, so "max over next actions of the interpolated Q" reads 2^d short rows of one
/// block (values[vertexCount * stateActionBegin[s] + v * n_s + j] for s's j-th action).
/// Saved as NumPy float32 arrays of shape (actions, vertices), row a = action a's table.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "mgrl/core/huge_pages.hpp"

#include "mgrl/graph/state_action_model.hpp"

namespace mgrl {

class QTable {
 public:
  QTable() = default;
  /// All zeros, for the model's actions and `vertexCount` vertices.
  QTable(const StateActionModel& model, std::size_t vertexCount);

  std::size_t vertexCount() const { return vertexCount_; }
  std::size_t actionCount() const { return actionBase_.size(); }
  std::size_t stateCount() const { return stateBegin_.size() - 1; }
  std::size_t actionsOf(std::size_t s) const { return stateBegin_[s + 1] - stateBegin_[s]; }

  float& at(std::size_t action, std::size_t vertex) { return values_[index(action, vertex)]; }
  float at(std::size_t action, std::size_t vertex) const { return values_[index(action, vertex)]; }
  std::size_t index(std::size_t action, std::size_t vertex) const {
    return actionBase_[action] + vertex * actionStride_[action];
  }
  /// The values of state s's out-actions at vertex v (actionsOf(s) floats).
  const float* row(std::size_t s, std::size_t v) const { return values_.data() + rowIndex(s, v); }
  float* row(std::size_t s, std::size_t v) { return values_.data() + rowIndex(s, v); }
  std::size_t rowIndex(std::size_t s, std::size_t v) const {
    return vertexCount_ * stateBegin_[s] + v * (stateBegin_[s + 1] - stateBegin_[s]);
  }

  std::span<float> values() { return {values_.data(), size_}; }
  std::span<const float> values() const { return {values_.data(), size_}; }
  std::size_t bytes() const { return size_ * sizeof(float); }

  /// Zero floats after the last value, so vector code may read a whole register past the
  /// end of any row.
  static constexpr std::size_t kPadding = 16;

  /// Row-major (actions, vertices), as saved.
  std::vector<float> actionMajor() const;
  /// The inverse of actionMajor(); throws mgrl::Error if the size does not match.
  void setActionMajor(std::span<const float> values);

  bool operator==(const QTable& other) const = default;

 private:
  std::size_t vertexCount_ = 0;
  std::vector<std::uint32_t> stateBegin_;                ///< copy of the model's stateActionBegin
  std::vector<std::uint64_t> actionBase_;                ///< index of (action, vertex 0)
  std::vector<std::uint32_t> actionStride_;              ///< n_s of the action's state
  std::size_t size_ = 0;                                 ///< actions x vertices
  std::vector<float, HugePageAllocator<float>> values_;  ///< size_ + kPadding
};

}  // namespace mgrl
