#pragma once
/// \file
/// A behaviour as a scenario names it (scenarios/README.md, `behaviors:`): its weight and
/// activation for the combined controller and its plugin blocks, still YAML, for the
/// registries to build (mgrl/learning/behavior.hpp).
#include <cstdint>
#include <string>
#include <string_view>

#include "mgrl/core/config.hpp"

namespace mgrl {

/// When a behaviour takes part in the combined controller (paper sec. 5): always, or only
/// while the target is inside its grid (the paper's hit behaviour).
enum class Activation { Always, TargetInside };
Activation parseActivation(std::string_view name);
std::string_view activationName(Activation activation);

/// The most stances a scenario may number (`stance: 0` to `stance: 15`).
constexpr int kMaxStances = 16;

/// Whether a behaviour of `stance` (-1: none) counts for a target of `held` (TargetState::
/// stance, -1: none held, so every behaviour counts).
inline bool stanceActive(int stance, std::int32_t held) { return stance < 0 || held < 0 || stance == held; }

/// One entry of `behaviors:` (scenarios/README.md): plugin blocks are kept as YAML and
/// built by the registries of the application (mgrl/learning/behavior.hpp).
struct BehaviorSpec {
  std::string name;
  std::string description;
  double weight = 1;
  Activation activation = Activation::Always;
  ConfigNode node;                                       ///< the behaviour's block
  ConfigNode discretizer, reward, environment, learner;  ///< environment may be absent (static_target)
  ConfigNode success =
      ConfigNode::parse("", "success");  ///< may be absent (mgrl/learning/success.hpp: implied by the reward)
  /// `stance: k`: active only while the fighter holds stance k; -1: always.
  int stance = -1;
};

}  // namespace mgrl
