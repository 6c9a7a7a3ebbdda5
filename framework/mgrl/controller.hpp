#pragma once
/// \file
/// The runtime choice (paper sec. 5): at a state, score each out-action by the weighted sum
/// of the active behaviours' Q values interpolated at the target, and take the best. A
/// behaviour with activation `always` is evaluated at the target clamped into its grid (so
/// a far target still pulls the avatar its way); a `target_inside` one only while the
/// target is inside its grid (the paper's hit behaviour).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "mgrl/discretizer.hpp"
#include "mgrl/q_table.hpp"
#include "mgrl/reward.hpp"
#include "mgrl/scenario.hpp"

namespace mgrl {

struct PolicyPart {
  const Discretizer* grid = nullptr;
  const QTable* table = nullptr;
  double weight = 1;
  Activation activation = Activation::Always;
};

class PolicyController {
 public:
  PolicyController(const StateActionModel& model, std::vector<PolicyPart> parts);

  /// The greedy action at state s with the target at e (avatar frame); ties go to the
  /// lowest action index. If no behaviour is active, the state's first action.
  std::size_t choose(std::uint32_t s, const Eigen::Vector3d& e);
  /// The combined scores of s's out-actions from the last choose() (for views and tests).
  std::span<const float> scores() const { return {buffer_.data(), count_}; }

 private:
  const StateActionModel& model_;
  std::vector<PolicyPart> parts_;
  std::vector<float> buffer_;  ///< scores, padded for vector code
  std::size_t count_ = 0;      ///< out-actions of the last state
};

}  // namespace mgrl

namespace mgrl {

/// One behaviour as the online search sees it: its reward, not a learned table.
struct SearchPart {
  const Discretizer* grid = nullptr;  ///< for `target_inside` activation
  const Reward* reward = nullptr;
  double weight = 1;
  Activation activation = Activation::Always;
};

/// The baseline precomputation replaces (Lee et al. 2002, as the paper compares with): at
/// each decision, search the graph `horizon` actions deep from the current state, with the
/// target moved along by the environment model, for the action sequence with the largest
/// discounted sum of the active behaviours' weighted rewards; take its first action. No
/// learned values: a leaf is worth 0. Cost grows as (actions per state)^horizon.
class OnlineSearchController {
 public:
  OnlineSearchController(const StateActionModel& model, const EnvironmentModel& environment,
                         std::vector<SearchPart> parts, int horizon, double gamma);

  /// The first action of the best sequence; ties go to the lowest action index.
  std::size_t choose(std::uint32_t s, const Eigen::Vector3d& e);
  /// Actions expanded by the last choose().
  std::size_t expanded() const { return expanded_; }

 private:
  double value(std::uint32_t s, const Eigen::Vector3d& e, int depth);
  double reward(std::size_t a, const Eigen::Vector3d& e) const;

  const StateActionModel& model_;
  const EnvironmentModel& environment_;
  std::vector<SearchPart> parts_;
  int horizon_;
  std::vector<double> discount_;  ///< per action: gamma^(frames)
  std::size_t expanded_ = 0;
};

}  // namespace mgrl
