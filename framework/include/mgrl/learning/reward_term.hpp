#pragma once
/// \file
/// The reward-term seam (scenarios/README.md, "reward terms"): one term of the `terms`
/// reward, a signal s_k(t) in [0, 1] at each frame t of an action, which the reward weighs
/// and combines over the frames. Term kinds register in BehaviorPlugins::terms like the
/// other plug-ins; a term that success criteria can test registers its condition (a
/// measure against a threshold) under the same name in BehaviorPlugins::conditions.
#include <cstddef>

#include <Eigen/Core>

#include "mgrl/core/error.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl {

/// What a term may read at frame t of action `action` (t = 1: the first frame after the
/// decision).
struct TermFrame {
  const StateActionModel& model;
  std::size_t action;
  std::size_t t;
  std::size_t frame;              ///< the global action-frame index of t
  const Eigen::Vector3d& target;  ///< where the target is at t (a moving one has moved)
  const TargetState& state;       ///< the environment state at the decision
  double startDistance;           ///< the pelvis's ground distance to the target at the decision
  /// A learned opponent: what it plays at this frame; `target` is then its head (its root at
  /// the target's height without a head). Null for other environments.
  const OpponentFrame* opponent = nullptr;
};

class Term {
 public:
  virtual ~Term() = default;
  /// Finds what the term reads in `m` (a joint, the opponent's strikes) before any
  /// signal(). Throws TermError naming the term's key at fault.
  virtual void bind(const StateActionModel&) {}
  /// s_k(t), in [0, 1].
  virtual double signal(const TermFrame& f) const = 0;
  /// True for a cost: the reward subtracts w_k s_k(t) instead of adding it (struck).
  virtual bool cost() const { return false; }
  /// True if signal() reads per-joint arrays of the bound model (the reward then refuses
  /// a model with another joint count).
  virtual bool readsJoints() const { return false; }
};

/// A term's binding failed at one of its keys ("point", "effector"): the reward reports
/// it there.
using TermError = KeyError;

/// The term kinds: `term: NAME` and the parameters it reads (a factory's Params also hold
/// `weight`, which the reward reads). A factory may refuse a combination of parameters
/// with Params::fail().
using TermRegistry = Registry<Term>;
using TermKind = TermRegistry::Entry;

}  // namespace mgrl
