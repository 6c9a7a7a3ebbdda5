#pragma once
/// \file
/// The controllers a session can run (paper sec. 5 and 6.6): a registry of their names,
/// what they need and how to make them (filled by the composition root, app/builtins, like
/// the other plug-ins' registries), one check of a choice for the command line and the
/// viewer's protocol, and one way to make them.
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "mgrl/runtime/controller.hpp"

namespace mgrl {

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

/// What the controllers are made from: the session's model, tables and rewards.
struct ControllerParts {
  const StateActionModel* model = nullptr;
  std::vector<PolicyPart> policy;                 ///< trained tables (empty: no bundle)
  std::vector<SearchPart> search;                 ///< the behaviours' rewards
  const EnvironmentModel* environment = nullptr;  ///< how the search moves the target
  double gamma = 0.97;
  Variety variety;  ///< the policy's choice among near-best actions ({}: greedy)
};

/// The runtime seam's registry (DESIGN.md sec. 4): a snake_case name maps to what the
/// controller needs and a factory. Not a Registry<>: a controller is chosen on the command
/// line or by the viewer's page with a ControllerChoice, not from a YAML block.
class ControllerRegistry {
 public:
  /// Makes a controller of a checked choice from parts that have what it needs
  /// (requireParts()); one instance serves one thread.
  using Factory = std::function<std::unique_ptr<Controller>(const ControllerChoice&, const ControllerParts&)>;
  struct Entry {
    std::string name;
    std::string summary;       ///< one line for `mgrl list`
    bool needsPolicy = false;  ///< needs a trained policy bundle (ControllerParts::policy)
    bool searches = false;     ///< reads the search horizon
    Factory make;
  };

  /// Adds a controller; a second one of the same name is a programming error
  /// (std::logic_error).
  void add(Entry entry);
  /// The entry named `name`, or null.
  const Entry* find(std::string_view name) const;
  /// In registration order (the order `mgrl list` shows them).
  const std::vector<Entry>& entries() const { return entries_; }
  /// The registered names, in registration order.
  std::vector<std::string> names() const;

 private:
  std::vector<Entry> entries_;
};

/// The names of `controllers` as a sentence lists them, "policy, online_search or random"
/// (for help texts); those that need a policy bundle left out with `withoutPolicy`.
std::string controllerAlternatives(const ControllerRegistry& controllers, bool withoutPolicy = false);

/// Throws mgrl::Error (`--controller: expected one of: policy, online_search, random,
/// found 'x'`, `--horizon: expected a search depth in actions in [1, 8], found 9`, ...)
/// unless `choice` names a controller of `controllers` with settings in range.
void checkControllerChoice(const ControllerRegistry& controllers, const ControllerChoice& choice,
                           const ControllerFields& fields = {});

/// Throws mgrl::Error unless `parts` has what the registered controller `choice` names
/// needs (tables for one that needs a policy, such as `policy`); unknown names as
/// checkControllerChoice().
void requireParts(const ControllerRegistry& controllers, const ControllerChoice& choice, const ControllerParts& parts);
/// A new controller of the checked `choice`, made by its entry in `controllers`. Throws
/// mgrl::Error for an unknown name (as checkControllerChoice()) or parts it cannot be made
/// from (requireParts()).
std::unique_ptr<Controller> makeController(const ControllerRegistry& controllers, const ControllerChoice& choice,
                                           const ControllerParts& parts);

}  // namespace mgrl
