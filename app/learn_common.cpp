#include "learn_common.hpp"

#include <fmt/format.h>

#include "mgrl/behavior.hpp"
#include "mgrl/motion_io.hpp"
#include "mgrl/data_paths.hpp"
#include "plugins.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string humanCount(double n) {
  if (n >= 1e9) return fmt::format("{:.2f} G", n / 1e9);
  if (n >= 1e6) return fmt::format("{:.2f} M", n / 1e6);
  if (n >= 1e3) return fmt::format("{:.1f} k", n / 1e3);
  return fmt::format("{:.0f} ", n);
}

std::string setFlags(const std::vector<std::string>& sets) {
  std::string text;
  for (const std::string& s : sets) text += fmt::format(" --set {}", s);
  return text;
}

// The scenario with its behaviours checked: every mistake that needs no graph is found
// before the graph is built or loaded.
Scenario checkedScenario(const LearnOptions& options) {
  Scenario scenario = loadScenario(options.scenario, dataDirectory(options.dataDir), options.sets);
  if (scenario.behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour (see scenarios/README.md), "
                       "found none");
  checkBehaviors(scenario, plugins());
  return scenario;
}


Loaded load(const LearnOptions& options, Scenario scenario) {
  GraphOptions graphOptions;
  graphOptions.cacheDir = options.cacheDir;
  graphOptions.log = options.log;
  GraphResult graph = obtainGraph(scenario, graphOptions);
  return {std::move(scenario), std::move(graph)};
}

// The refusals eval and simulate can make from the manifest alone, made before the graph is loaded so
// that they are the only line on stderr. loadPolicyBundle() checks everything afterwards.
void precheckPolicy(const fs::path& dir, const Scenario& scenario, const LearnOptions& options) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw Error(fmt::format("{}: no policy bundle here: run `mgrl train {}{}` first (or pass --policy DIR)",
                            dir.string(), options.scenario.string(), setFlags(options.sets)));
  json manifest;
  try {
    manifest = json::parse(readFile(dir / "manifest.json"));
  } catch (const std::exception&) {
    return;  // the full load says what is wrong
  }
  if (!manifest.is_object() || !manifest.contains("graph_key") || !manifest["graph_key"].is_string() ||
      !manifest.contains("behaviors") || !manifest["behaviors"].is_object())
    return;
  const std::string graphKey = graphCacheKey(scenario);
  const std::string found = manifest["graph_key"].get<std::string>();
  if (found != graphKey)
    throw Error(fmt::format("{}: expected graph key '{}', found '{}': the policy was made for another graph; "
                            "retrain with mgrl train {}{}",
                            (dir / "manifest.json").string(), graphKey.substr(0, 16), found.substr(0, 16),
                            options.scenario.string(), setFlags(options.sets)));
  for (const BehaviorSpec& spec : scenario.behaviors) {
    const json& entry = manifest["behaviors"].contains(spec.name) ? manifest["behaviors"][spec.name] : json();
    if (entry.is_null())
      throw Error(fmt::format("{}: expected a trained table for behaviour '{}' that the scenario asks for, found "
                              "none; run mgrl train {} --behavior {}{}",
                              dir.string(), spec.name, options.scenario.string(), spec.name, setFlags(options.sets)));
    const std::string key = behaviorConfigAndKey(spec, plugins(), graphKey).second;
    if (entry.is_object() && entry.contains("key") && entry["key"].is_string() && entry["key"] != key)
      throw Error(fmt::format("{}: behaviour '{}' was trained with other settings than the scenario's now (key {} "
                              "vs {}); retrain with mgrl train {} --behavior {}{}",
                              dir.string(), spec.name, entry["key"].get<std::string>().substr(0, 16),
                              key.substr(0, 16), options.scenario.string(), spec.name, setFlags(options.sets)));
  }
}


std::vector<PolicyPart> policyParts(const fs::path& dir, const std::vector<Behavior>& behaviors,
                                    const GraphResult& graph, const LearnOptions& options, PolicyBundle& bundle) {
  bundle = loadPolicyBundle(dir, graph.model, graph.key);
  std::vector<PolicyPart> parts;
  for (const Behavior& b : behaviors) {
    const auto found = bundle.behaviors.find(b.name);
    if (found == bundle.behaviors.end())
      throw Error(fmt::format("{}: expected a trained table for behaviour '{}' that the scenario asks for, found "
                              "none; run mgrl train {} --behavior {}{}",
                              dir.string(), b.name, options.scenario.string(), b.name, setFlags(options.sets)));
    if (found->second.key != b.key)
      throw Error(fmt::format("{}: behaviour '{}' was trained with other settings than the scenario's now (key {} "
                              "vs {}); retrain with mgrl train {} --behavior {}{}",
                              dir.string(), b.name, found->second.key.substr(0, 16), b.key.substr(0, 16),
                              options.scenario.string(), b.name, setFlags(options.sets)));
    parts.push_back({b.discretizer.get(), &found->second.table, b.weight, b.activation});
  }
  return parts;
}

}  // namespace mgrl::app
