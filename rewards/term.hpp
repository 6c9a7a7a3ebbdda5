#pragma once
/// \file
/// The built-in reward terms (the seam: mgrl/learning/reward_term.hpp). A term kind is one
/// file here (distance.cpp, facing.cpp, ...) with its register function, called in
/// register.cpp; a term that success criteria can test registers its condition (a measure
/// against a threshold) there too. This header also has the helpers the term files share.
#include <cstddef>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "mgrl/core/error.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/learning/reward.hpp"
#include "mgrl/learning/reward_term.hpp"
#include "mgrl/learning/signals.hpp"
#include "mgrl/learning/success.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl::rewards {

/// Where the term files register: their term kinds and, for those that have one, their
/// success condition (mgrl/learning/success.hpp) under the same name.
struct Vocabulary {
  TermRegistry& terms;
  ConditionRegistry& conditions;
};

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
void registerReversal(Vocabulary& v);

/// Binds `point` to `m`, or throws TermError at "point" saying which roles and joints `m` has.
void bindPoint(const StateActionModel& m, BodyPoint& point);

/// The body point an opponent's strikes reach (avoid, struck): `point` read from `p`, which
/// must name a joint (Params::fail at "point" otherwise).
BodyPoint struckPoint(const Params& p);
/// Where the opponent's strikes of the `effectors` reach in `m` (a field exact up to
/// `cap`), or TermError at "effector" when `m` has none of them.
std::shared_ptr<const StrikeReach> bindReach(const StateActionModel& m, std::uint8_t effectors, double cap);

}  // namespace mgrl::rewards
