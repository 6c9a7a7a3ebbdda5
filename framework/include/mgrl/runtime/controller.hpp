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

#include "mgrl/core/random.hpp"
#include "mgrl/learning/behavior_spec.hpp"
#include "mgrl/learning/discretizer.hpp"
#include "mgrl/learning/environment_model.hpp"
#include "mgrl/learning/q_table.hpp"
#include "mgrl/learning/reward.hpp"

namespace mgrl {

/// The runtime seam (DESIGN.md sec. 4): which action to take at a state. Controllers keep
/// scratch buffers, so one instance serves one thread.
class Controller {
 public:
  virtual ~Controller() = default;
  /// The action (a global action index leaving s) to take at state s with the target at e
  /// in the avatar frame; `rng` drives any random choice (variety, the random controller).
  virtual std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng) = 0;
  /// The same among the allowed out-actions only: allowed[j] != 0 for the j-th action
  /// leaving s (the world rules out actions whose root path runs into another body). At
  /// least one must be allowed (mgrl::Error otherwise). A controller that scores actions
  /// takes the best allowed one, as it would among all.
  virtual std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng,
                             std::span<const std::uint8_t> allowed) = 0;
};

/// Takes a uniformly random out-action: the floor every controller is measured against.
class RandomController final : public Controller {
 public:
  explicit RandomController(const StateActionModel& model) : model_(model) {}
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng) override;
  /// Uniformly among the allowed actions.
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng, std::span<const std::uint8_t> allowed) override;

 private:
  const StateActionModel& model_;
};

/// The `opponent` environment model's scripted pursuer (environments/opponent.cpp)
/// played with the graph's own actions, so that a dodge scene's opponent is a body that
/// moves and strikes. The same rule as eval's trials against an avatar
/// (framework/session/trials.cpp), greedy over the out-actions: with its target (the
/// avatar it pursues: that avatar's head) at e, the lowest cost
///   place + kTurnCost x |facing error at the action's end| - kPunchWeight x punch,
/// where place is how far the action ends from `stopDistance` to the target on the ground
/// (`stand`: how far the action moves it; eval's trials measure from its start, which a
/// controller shared by many avatars does not keep), and punch (punchScore) how near one of the
/// action's effective fist tips (paper sec. 6.2) comes to the target. Walking speed is the
/// capture's, not the model's `speed`: the model is this avatar's abstraction for the tables.
class PursueController final : public Controller {
 public:
  /// Throws mgrl::Error for a stopDistance that is negative or not finite.
  PursueController(const StateActionModel& model, double stopDistance, bool stand = false);
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng) override;
  /// The same among the allowed actions; ties go to the lowest action index.
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng, std::span<const std::uint8_t> allowed) override;

  /// 1 - (the nearest fist tip's distance to `aim`) / kPunchReach, at least 0: how well one
  /// of `hits` (in the decision's frame, as `aim`) strikes it.
  static double punchScore(std::span<const ActionHit> hits, const Eigen::Vector3d& aim);
  static constexpr double kTurnCost = 0.5;    ///< m of place a radian of facing error costs
  static constexpr double kPunchWeight = 2;   ///< m of place a perfect punch is worth
  static constexpr double kPunchReach = 0.5;  ///< m: a fist tip this far from the aim scores 0

 private:
  const StateActionModel& model_;
  double stopDistance_;
  bool stand_;
};

/// Variety at run time (paper sec. 5: "pick at random among a few top candidates"): the
/// candidates are the `topK` best-scoring actions, less those scoring below
/// best - margin * |best| when margin > 0; one is drawn uniformly. topK = 1 is greedy.
struct Variety {
  int topK = 1;
  double margin = 0;
};

struct PolicyPart {
  const Discretizer* grid = nullptr;
  const QTable* table = nullptr;
  double weight = 1;
  Activation activation = Activation::Always;
  int stance = -1;  ///< active only while the target's stance is this (-1: always)
};

class PolicyController final : public Controller {
 public:
  PolicyController(const StateActionModel& model, std::vector<PolicyPart> parts, Variety variety = {});

  /// The greedy action at state s with the target at e (avatar frame); ties go to the
  /// lowest action index. If no behaviour is active, the state's first action.
  std::size_t choose(std::uint32_t s, const TargetState& e);
  /// With variety (see Variety): one of the top candidates, drawn with `rng`; exactly
  /// choose(s, e) when topK is 1.
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng) override;
  /// The same ranking (greedy, or top k within the margin) over the allowed actions only.
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng& rng, std::span<const std::uint8_t> allowed) override;
  /// The combined scores of s's out-actions from the last choose() (for views and tests).
  std::span<const float> scores() const { return {buffer_.data(), count_}; }

 private:
  void score(std::uint32_t s, const TargetState& e);
  std::size_t pick(std::uint32_t s, Rng& rng, std::span<const std::uint8_t> allowed);

  const StateActionModel& model_;
  std::vector<PolicyPart> parts_;
  Variety variety_;
  std::vector<float> buffer_;          ///< scores, padded for vector code
  std::size_t count_ = 0;              ///< out-actions of the last state
  std::vector<std::uint32_t> ranked_;  ///< scratch for variety
};

}  // namespace mgrl

namespace mgrl {

/// One behaviour as the online search sees it: its reward, not a learned table.
struct SearchPart {
  const Discretizer* grid = nullptr;  ///< for `target_inside` activation
  const Reward* reward = nullptr;
  double weight = 1;
  Activation activation = Activation::Always;
  int stance = -1;  ///< as PolicyPart::stance
};

/// How far the online search looks: `actions` actions deep, or, when seconds > 0, every
/// sequence until it has played at least `seconds` of motion (at most `actions` deep).
struct SearchHorizon {
  int actions = 3;
  double seconds = 0;
};

/// The baseline precomputation replaces (Lee et al. 2002, as the paper compares with): at
/// each decision, search the graph from the current state to the horizon, with the target
/// moved along by the environment model, for the action sequence with the largest
/// discounted sum of the active behaviours' weighted rewards; take its first action. No
/// learned values: a leaf is worth 0. Cost grows as (actions per state)^depth.
class OnlineSearchController final : public Controller {
 public:
  OnlineSearchController(const StateActionModel& model, const EnvironmentModel& environment,
                         std::vector<SearchPart> parts, int horizon, double gamma);
  OnlineSearchController(const StateActionModel& model, const EnvironmentModel& environment,
                         std::vector<SearchPart> parts, SearchHorizon horizon, double gamma);

  /// The first action of the best sequence; ties go to the lowest action index.
  std::size_t choose(std::uint32_t s, const TargetState& e);
  /// The same (the search is deterministic; `rng` is unused).
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng&) override { return choose(s, e); }
  /// The first action of the best sequence that starts with an allowed action.
  std::size_t choose(std::uint32_t s, const TargetState& e, Rng&, std::span<const std::uint8_t> allowed) override;
  /// Actions expanded by the last choose().
  std::size_t expanded() const { return expanded_; }

 private:
  /// Best discounted value from s with `depth` more actions allowed and `frames` more
  /// frames to cover (frames <= 0: the time horizon is reached).
  double value(std::uint32_t s, const TargetState& e, int depth, double frames);
  /// Action a's reward plus the discounted best value after it, with depth - 1 actions
  /// and the frames left after it.
  double backup(std::size_t a, const TargetState& e, int depth, double frames);
  /// The first action of the best sequence among the allowed ones (every one when
  /// `allowed` is empty); ties go to the lowest index.
  std::size_t bestFirstAction(std::uint32_t s, const TargetState& e, std::span<const std::uint8_t> allowed);
  double reward(std::size_t a, const TargetState& e) const;

  const StateActionModel& model_;
  const EnvironmentModel& environment_;
  std::vector<SearchPart> parts_;
  int horizon_;
  double horizonFrames_;          ///< +inf for a horizon in actions
  std::vector<double> discount_;  ///< per action: gamma^(frames)
  std::size_t expanded_ = 0;
};

}  // namespace mgrl
