#pragma once
/// \file
/// One term of the `terms` reward (rewards/terms.cpp; scenarios/README.md, "reward
/// terms"): a signal s_k(t) in [0, 1] at each frame t of an action, which the reward
/// weighs and combines over the frames. A term kind is one file here (distance.cpp,
/// facing.cpp, ...) with its register function, called in register.cpp; a term that
/// success criteria can test registers its condition (a measure against a threshold) there too.
#include <cstddef>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "mgrl/core/error.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/learning/reward.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/success.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl::rewards {

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
  /// A learned opponent: what it plays at this frame; `target` is then its head
  /// (its root at the target's height without a head). Null for other environments.
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

/// What the term files register: their term kinds and, for those that have one, their
/// success condition (mgrl/learning/success.hpp) under the same name.
struct Vocabulary {
  TermRegistry terms{"reward term"};
  ConditionRegistry conditions{"success term"};
};

/// Every term kind, in the order `mgrl list` shows them (register.cpp).
const std::vector<TermKind>& termKinds();
const TermRegistry& termRegistry();
/// Every success condition kind, in the same order.
const ConditionRegistry& conditionRegistry();

/// The parameter every term has: its weight w_k in the frame's signal.
ParamSpec weightSpec();

/// The term files' register functions (register.cpp calls them in order).
void registerDistance(Vocabulary& v);
void registerFacing(Vocabulary& v);
void registerContact(Vocabulary& v);
void registerTravel(Vocabulary& v);
void registerEffort(Vocabulary& v);
void registerAvoid(Vocabulary& v);
void registerStruck(Vocabulary& v);

/// Binds `point` to `m`, or throws TermError at "point" saying which roles and joints `m` has.
void bindPoint(const StateActionModel& m, BodyPoint& point);

/// The body point an opponent's strikes reach (avoid, struck): `point` read from `p`, which
/// must name a joint (Params::fail at "point" otherwise).
BodyPoint struckPoint(const Params& p);
/// Where the opponent's strikes of the `effectors` reach in `m` (a field exact up to
/// `cap`), or TermError at "effector" when `m` has none of them.
std::shared_ptr<const StrikeReach> bindReach(const StateActionModel& m, std::uint8_t effectors, double cap);

}  // namespace mgrl::rewards
