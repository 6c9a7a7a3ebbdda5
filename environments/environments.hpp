#pragma once
/// \file
/// The environment-model plugins (DESIGN.md sec. 4): how the target moves relative to the
/// avatar under an action.
#include <memory>
#include <string>
#include <vector>

#include "mgrl/learning/environment_model.hpp"

namespace mgrl::environments {

/// Adds static_target (the paper's: the target stays put in the world), moving_target,
/// opponent and learned_opponent, in the order `mgrl list` shows them (register.cpp).
void registerAll(EnvironmentRegistry& registry);
/// Adds static_target and moving_target (environments/static_target.cpp).
void registerStaticTargets(EnvironmentRegistry& registry);
/// Adds opponent (environments/opponent.cpp).
void registerOpponent(EnvironmentRegistry& registry);
/// Adds learned_opponent (environments/learned_opponent.cpp).
void registerLearnedOpponent(EnvironmentRegistry& registry);

/// `opponent`: the target is another avatar of the same graph, standing at e.position on
/// the ground and facing e.heading (speed 0). After each of the avatar's actions it has
/// walked toward the avatar's end position at `speed` (pursue), stopping `stopDistance`
/// from it, and turned toward it by at most turnRate x the action's duration; all seen
/// from the action's end. Its facing turns with the avatar frame, so it is a grid's
/// interpolated heading axis, not a layer. A FacingOpponent; offers the ScriptedOpponent
/// the world plays it as.
class Opponent final : public EnvironmentModel, public FacingOpponent {
 public:
  Opponent(bool pursue, double speed, double stopDistance, double turnRate)
      : scripted_{!pursue, stopDistance}, speed_(speed), turnRate_(turnRate) {}
  std::string type() const override { return "opponent"; }
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;
  TargetState draw(const Eigen::Vector3d& position, Rng&) const override;

 protected:
  const void* capability(std::type_index type) const override {
    return offer(type, static_cast<const FacingOpponent*>(this), &scripted_);
  }

 private:
  ScriptedOpponent scripted_;  // pursue (not stand) to stopDistance, m
  double speed_, turnRate_;    // m/s, rad/s
};

/// A number no earlier call returned (from 1), thread-safe.
std::uint64_t freshGeneration();

/// `learned_opponent`: the target is another avatar of the same graph playing
/// graph actions (see learned_opponent.cpp for the state and how time is handled). Its
/// discrete state is TargetState::opponent = s * phases + b: the graph state s its current
/// action ends at and the phase bucket b of the frames left (0: about to arrive). A
/// FacingOpponent, a TrackedOpponent and a SelfPlayOpponent.
class LearnedOpponent final : public EnvironmentModel,
                              public FacingOpponent,
                              public TrackedOpponent,
                              public SelfPlayOpponent {
 public:
  LearnedOpponent(std::string policy, int phases, int rounds, bool averageRounds, double stopDistance, double reach,
                  double strikeBonus)
      : policy_(std::move(policy)),
        phases_(phases),
        rounds_(rounds),
        averageRounds_(averageRounds),
        stopDistance_(stopDistance),
        reach_(reach),
        strikeBonus_(strikeBonus) {}
  std::string type() const override { return "learned_opponent"; }
  void bind(const StateActionModel& m) override;
  TargetState next(const StateActionModel& model, std::size_t action, const TargetState& e) const override;
  TargetState draw(const Eigen::Vector3d& position, Rng& rng) const override;

  // TrackedOpponent
  std::size_t opponentStates() const override;
  int opponentPhases() const override { return phases_; }
  void track(const StateActionModel& model, std::size_t action, const TargetState& e,
             std::vector<OpponentFrame>& out) const override;

  // SelfPlayOpponent
  void playPolicy(const Discretizer* grid, std::shared_ptr<const QTable> table, const std::string& key) override;
  std::string policyKey() const override { return table_ ? key_ : "scripted"; }
  std::string policySource() const override { return policy_ == "scripted" ? "" : policy_; }
  int rounds() const override { return rounds_; }
  bool roundsAgainstAverage() const override { return averageRounds_; }

  /// `policy` as written: "scripted" or a bundle directory.
  const std::string& policy() const { return policy_; }
  /// The graph state s's representative incoming action (what the opponent is taken to be
  /// playing when only its end state and phase are known).
  std::uint32_t representative(std::uint32_t s) const { return representative_[s]; }
  /// The phase bucket of tau frames left of an action of `length` frames (tau in [1, length]).
  std::uint32_t phaseOf(std::uint32_t tau, std::uint32_t length) const;
  /// The frames left that phase b of state s stands for (the middle of the bucket on its
  /// representative action).
  std::uint32_t framesLeft(const StateActionModel& m, std::uint32_t s, std::uint32_t b) const;
  /// The opponent's decision at state s with its root at `self` (avatar decision frame), the
  /// avatar at frame t of `avatarAction`: the table's greedy action, or the scripted one.
  std::uint32_t choose(const StateActionModel& m, std::uint32_t s, const GroundMotion& self, std::size_t avatarAction,
                       std::uint32_t t, double height) const;

 protected:
  const void* capability(std::type_index type) const override {
    return offer(type, static_cast<const FacingOpponent*>(this), static_cast<const TrackedOpponent*>(this),
                 static_cast<const SelfPlayOpponent*>(this));
  }

 private:
  TargetState simulate(const StateActionModel& m, std::size_t action, const TargetState& e,
                       std::vector<OpponentFrame>* out) const;

  std::string policy_;
  int phases_, rounds_;
  bool averageRounds_;
  double stopDistance_, reach_, strikeBonus_;
  const StateActionModel* model_ = nullptr;
  std::vector<std::uint32_t> representative_;
  int head_ = -1;
  const Discretizer* grid_ = nullptr;
  std::shared_ptr<const QTable> table_;
  std::string key_;
  /// Unique to this object's binding and policy (a fresh one at each bind() and playPolicy()),
  /// so that next() reuses only a track() of the same opponent.
  std::uint64_t policyGeneration_ = freshGeneration();
  std::vector<double> cosYaw_, sinYaw_;  ///< per action: its turn's cosine and sine
};

}  // namespace mgrl::environments
