#pragma once
/// \file
/// The controllers a session can run (paper sec. 5 and 6.6), listed once: their names and
/// what they need, one check of a choice for the command line and the viewer's protocol,
/// and one way to make them.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "mgrl/runtime/controller.hpp"

namespace mgrl {

struct ControllerSpec {
  std::string name;
  std::string summary;
  bool needsPolicy = false;  ///< needs a trained policy bundle
  bool searches = false;     ///< reads the search horizon
};

/// policy, online_search, random: in the order `mgrl list` shows them.
const std::vector<ControllerSpec>& controllerSpecs();
/// The spec named `name`, or null.
const ControllerSpec* findController(std::string_view name);
/// Their names, in that order.
std::vector<std::string> controllerNames();

/// The online search's depth in actions is at most this (the cost grows as the actions per
/// state to this power), its horizon in seconds at most kMaxHorizonSeconds.
inline constexpr int kMaxHorizon = 8;
inline constexpr double kMaxHorizonSeconds = 5;

/// A controller and its settings as a user chooses them.
struct ControllerChoice {
  std::string name = "policy";
  int horizon = 3;            ///< online_search: depth in actions
  double horizonSeconds = 0;  ///< online_search: > 0 searches this much motion instead
};

/// How the fields are called where the choice came from, for the messages.
struct ControllerFields {
  std::string_view controller = "--controller";
  std::string_view horizon = "--horizon";
  std::string_view horizonSeconds = "--horizon-seconds";
};

/// Throws mgrl::Error (`--controller: expected one of: policy, online_search, random,
/// found 'x'`, `--horizon: expected a search depth in actions in [1, 8], found 9`, ...)
/// unless `choice` names a registered controller with settings in range.
void checkControllerChoice(const ControllerChoice& choice, const ControllerFields& fields = {});

/// What the controllers are made from: the session's model, tables and rewards.
struct ControllerParts {
  const StateActionModel* model = nullptr;
  std::vector<PolicyPart> policy;                 ///< trained tables (empty: no bundle)
  std::vector<SearchPart> search;                 ///< the behaviours' rewards
  const EnvironmentModel* environment = nullptr;  ///< how the search moves the target
  double gamma = 0.97;
  Variety variety;  ///< the policy's choice among near-best actions ({}: greedy)
};

/// Throws mgrl::Error unless `parts` has what `choice` needs (tables for `policy`).
void requireParts(const ControllerChoice& choice, const ControllerParts& parts);
/// A new controller of the checked `choice`. Throws mgrl::Error for `policy` without tables.
std::unique_ptr<Controller> makeController(const ControllerChoice& choice, const ControllerParts& parts);

}  // namespace mgrl
