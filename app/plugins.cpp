#include "plugins.hpp"

#include <fmt/format.h>

#include "discretizers/discretizers.hpp"
#include "learners/learners.hpp"
#include "rewards/rewards.hpp"

namespace mgrl::app {

const Plugins& plugins() {
  static const Plugins instance = [] {
    Plugins p;
    discretizers::registerAll(p.discretizers);
    rewards::registerAll(p.rewards);
    rewards::registerEnvironments(p.environments);
    learners::registerAll(p.learners);
    return p;
  }();
  return instance;
}

namespace {

template <class Registry>
void describe(std::string& text, const Registry& registry, std::string_view heading) {
  text += fmt::format("{}:\n", heading);
  for (const auto& entry : registry.entries()) {
    text += fmt::format("  {}: {}\n", entry.name, entry.summary);
    text += describeParams(entry.params, "      ");
  }
  text += "\n";
}

template <class Registry>
nlohmann::json toJson(const Registry& registry) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& entry : registry.entries()) {
    nlohmann::json params = nlohmann::json::array();
    for (const ParamSpec& spec : entry.params)
      params.push_back({{"name", spec.name}, {"default", spec.defaultText()}, {"range", spec.rangeText()},
                        {"unit", spec.unit}, {"help", spec.help}});
    list.push_back({{"name", entry.name}, {"summary", entry.summary}, {"parameters", params}});
  }
  return list;
}

}  // namespace

std::string listText(const Plugins& p) {
  std::string text;
  describe(text, p.discretizers, "discretizers (behaviors.NAME.discretizer.type)");
  describe(text, p.rewards, "rewards (behaviors.NAME.reward.type)");
  describe(text, p.environments, "environment models (behaviors.NAME.environment.type, default static_target)");
  describe(text, p.learners, "learners (behaviors.NAME.learner.type)");
  text += "Behaviour keys: description, weight (default 1), activation (always | target_inside), discretizer, "
          "reward, environment, learner. See scenarios/README.md.\n";
  return text;
}

nlohmann::json listJson(const Plugins& p) {
  return {{"discretizers", toJson(p.discretizers)},
          {"rewards", toJson(p.rewards)},
          {"environments", toJson(p.environments)},
          {"learners", toJson(p.learners)}};
}

}  // namespace mgrl::app
