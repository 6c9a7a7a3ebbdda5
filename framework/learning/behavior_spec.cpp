#include "mgrl/learning/behavior_spec.hpp"

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

Activation parseActivation(std::string_view name) {
  if (name == "always") return Activation::Always;
  if (name == "target_inside") return Activation::TargetInside;
  throw Error(fmt::format("expected an activation rule (always, target_inside), found {}", quoteToken(name)));
}

std::string_view activationName(Activation activation) {
  return activation == Activation::Always ? "always" : "target_inside";
}

}  // namespace mgrl
