#include "mgrl/session/controllers.hpp"

#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

void ControllerRegistry::add(Entry entry) {
  if (find(entry.name)) throw std::logic_error(fmt::format("controller '{}' registered twice", entry.name));
  entries_.push_back(std::move(entry));
}

const ControllerRegistry::Entry* ControllerRegistry::find(std::string_view name) const {
  for (const Entry& e : entries_)
    if (e.name == name) return &e;
  return nullptr;
}

std::vector<std::string> ControllerRegistry::names() const {
  std::vector<std::string> out;
  for (const Entry& e : entries_) out.push_back(e.name);
  return out;
}

std::string controllerAlternatives(const ControllerRegistry& controllers, bool withoutPolicy) {
  std::vector<std::string> names;
  for (const ControllerRegistry::Entry& e : controllers.entries())
    if (!(withoutPolicy && e.needsPolicy)) names.push_back(e.name);
  if (names.size() < 2) return names.empty() ? std::string() : names[0];
  const std::string last = names.back();
  names.pop_back();
  return fmt::format("{} or {}", fmt::join(names, ", "), last);
}

namespace {

// The entry `choice` names; for an unknown name, the message that lists the known ones.
const ControllerRegistry::Entry& entryFor(const ControllerRegistry& controllers, const ControllerChoice& choice,
                                          std::string_view field) {
  const ControllerRegistry::Entry* entry = controllers.find(choice.name);
  if (!entry)
    throw Error(fmt::format("{}: expected one of: {}, found {}", field, fmt::join(controllers.names(), ", "),
                            quoteToken(choice.name)));
  return *entry;
}

}  // namespace

void checkControllerChoice(const ControllerRegistry& controllers, const ControllerChoice& choice,
                           const ControllerFields& fields) {
  entryFor(controllers, choice, fields.controller);
  if (choice.horizon < 1 || choice.horizon > kMaxHorizon)
    throw Error(fmt::format("{}: expected a search depth in actions in [1, {}], found {}", fields.horizon, kMaxHorizon,
                            choice.horizon));
  if (!(choice.horizonSeconds >= 0 && choice.horizonSeconds <= kMaxHorizonSeconds))
    throw Error(fmt::format("{}: expected seconds of motion to search in [0, {:g}], found {}", fields.horizonSeconds,
                            kMaxHorizonSeconds, choice.horizonSeconds));
}

void requireParts(const ControllerRegistry& controllers, const ControllerChoice& choice, const ControllerParts& parts) {
  if (entryFor(controllers, choice, ControllerFields{}.controller).needsPolicy && parts.policy.empty())
    throw Error(fmt::format("--controller {}: expected a trained policy bundle, found none (train one with mgrl train)",
                            choice.name));
}

std::unique_ptr<Controller> makeController(const ControllerRegistry& controllers, const ControllerChoice& choice,
                                           const ControllerParts& parts) {
  requireParts(controllers, choice, parts);
  return entryFor(controllers, choice, ControllerFields{}.controller).make(choice, parts);
}

}  // namespace mgrl
