#include "plugins.hpp"

#include <fmt/format.h>

#include "mgrl/runtime/world.hpp"
#include "mgrl/session/controllers.hpp"

namespace mgrl::app {

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

nlohmann::json paramsJson(const ParamSpecs& specs) {
  nlohmann::json params = nlohmann::json::array();
  for (const ParamSpec& spec : specs)
    params.push_back({{"name", spec.name}, {"default", spec.defaultText()}, {"range", spec.rangeText()},
                      {"unit", spec.unit}, {"help", spec.help}});
  return params;
}

template <class Registry>
nlohmann::json toJson(const Registry& registry) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& entry : registry.entries()) {
    list.push_back({{"name", entry.name}, {"summary", entry.summary}, {"parameters", paramsJson(entry.params)}});
  }
  return list;
}

}  // namespace

std::string listText(const Plugins& p) {
  std::string text;
  describe(text, p.discretizers, "discretizers (behaviors.NAME.discretizer.type)");
  describe(text, p.rewards, "rewards (behaviors.NAME.reward.type)");
  text += "reward terms (behaviors.NAME.reward.terms, with type: terms):\n";
  for (const TermKind& kind : p.terms.entries()) {
    text += fmt::format("  term: {}  {}\n", kind.name, kind.summary);
    text += describeParams(kind.params, "    ");
  }
  text += "\n";
  describe(text, p.environments, "environment models (behaviors.NAME.environment.type, default static_target)");
  describe(text, p.learners, "learners (behaviors.NAME.learner.type)");
  text += "Behaviour keys: description, weight (default 1), activation (always | target_inside), discretizer, "
          "reward, environment, learner, success. See scenarios/README.md.\n";
  text +=
      "success (behaviors.NAME.success; eval's trials stop when one behaviour's is met):\n"
      "  {term: NAME, ...}: a reward term's measure against a threshold; the keys it shares with the term\n"
      "  (all but the threshold) default to the behaviour's reward term of that kind. hold_s: S beside one\n"
      "  condition, or {all: [conditions], hold_s: S}: held S seconds. No success: the behaviour's contact reward (the "
      "paper's hit), else an\n"
      "  effective punch within 0.15 m.\n";
  describe(text, p.conditions, "success terms (behaviors.NAME.success.term)");
  text += "controllers (mgrl eval / simulate --controller):\n";
  for (const ControllerRegistry::Entry& entry : p.controllers.entries())
    text += fmt::format("  {}: {}\n", entry.name, entry.summary);
  text += "\n";
  text += "world (mgrl simulate; scenario section world:):\n";
  text += describeParams(worldParamSpecs(), "      ");
  return text;
}

nlohmann::json listJson(const Plugins& p) {
  return {{"discretizers", toJson(p.discretizers)}, {"rewards", toJson(p.rewards)},
          {"reward_terms", toJson(p.terms)},        {"success_terms", toJson(p.conditions)},
          {"environments", toJson(p.environments)}, {"learners", toJson(p.learners)},
          {"controllers", p.controllers.names()},   {"world", paramsJson(worldParamSpecs())}};
}

}  // namespace mgrl::app
