#include "mgrl/session/controllers.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

const std::vector<ControllerSpec>& controllerSpecs() {
  static const std::vector<ControllerSpec> specs = {
      {"policy", "the trained behaviours' weighted Q values, with the world's variety in simulate", true, false},
      {"online_search",
       "depth-limited graph search for the best discounted reward (--horizon, --horizon-seconds)", false, true},
      {"random", "a uniformly random out-action", false, false},
  };
  return specs;
}

const ControllerSpec* findController(std::string_view name) {
  for (const ControllerSpec& spec : controllerSpecs())
    if (spec.name == name) return &spec;
  return nullptr;
}

std::vector<std::string> controllerNames() {
  std::vector<std::string> names;
  for (const ControllerSpec& spec : controllerSpecs()) names.push_back(spec.name);
  return names;
}

void checkControllerChoice(const ControllerChoice& choice, const ControllerFields& fields) {
  if (!findController(choice.name))
    throw Error(fmt::format("{}: expected one of: {}, found {}", fields.controller, fmt::join(controllerNames(), ", "),
                            quoteToken(choice.name)));
  if (choice.horizon < 1 || choice.horizon > kMaxHorizon)
    throw Error(fmt::format("{}: expected a search depth in actions in [1, {}], found {}", fields.horizon, kMaxHorizon,
                            choice.horizon));
  if (!(choice.horizonSeconds >= 0 && choice.horizonSeconds <= kMaxHorizonSeconds))
    throw Error(fmt::format("{}: expected seconds of motion to search in [0, {:g}], found {}", fields.horizonSeconds,
                            kMaxHorizonSeconds, choice.horizonSeconds));
}

void requireParts(const ControllerChoice& choice, const ControllerParts& parts) {
  if (choice.name == "policy" && parts.policy.empty())
    throw Error("--controller policy: expected a trained policy bundle, found none (train one with mgrl train)");
}

std::unique_ptr<Controller> makeController(const ControllerChoice& choice, const ControllerParts& parts) {
  requireParts(choice, parts);
  if (choice.name == "policy") return std::make_unique<PolicyController>(*parts.model, parts.policy, parts.variety);
  if (choice.name == "online_search")
    return std::make_unique<OnlineSearchController>(*parts.model, *parts.environment, parts.search,
                                                    SearchHorizon{choice.horizon, choice.horizonSeconds}, parts.gamma);
  if (choice.name == "random") return std::make_unique<RandomController>(*parts.model);
  checkControllerChoice(choice);  // says what is known
  throw Error(fmt::format("--controller: no controller {}", quoteToken(choice.name)));
}

}  // namespace mgrl
