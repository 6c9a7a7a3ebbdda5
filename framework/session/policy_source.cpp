// Which scenario and which policy bundle a session opens (DESIGN.md sec. 5): the scenario
// checked before any graph is loaded, the bundle found (the default one of the scenario,
// or --policy), refused from its manifest alone when it cannot serve, or adopted with the
// settings it was trained with; its tables bound to the behaviours.
#include "mgrl/session/policy_source.hpp"

#include <algorithm>
#include <exception>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/learning/behavior_spec.hpp"
#include "mgrl/scenario/behaviors.hpp"

namespace mgrl {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string setFlags(const std::vector<std::string>& sets) {
  std::string text;
  for (const std::string& s : sets) text += fmt::format(" --set {}", s);
  return text;
}

// The scenario with its behaviours checked: every mistake that needs no graph is found
// before the graph is built or loaded.
Scenario checkedScenario(const SessionOptions& options) {
  Scenario scenario = loadScenario(options.scenario, dataDirectory(options.dataDir), options.sets);
  if (scenario.behaviors.empty())
    scenario.root.fail("expected a 'behaviors' section naming at least one behaviour (see scenarios/README.md), "
                       "found none");
  checkBehaviors(scenario, requirePlugins(options.plugins, "SessionOptions::plugins"));
  return scenario;
}


// The refusals eval and simulate can make from the manifest alone, made before the graph is loaded so
// that they are the only line on stderr. loadPolicyBundle() checks everything afterwards.
void precheckPolicy(const fs::path& dir, const Scenario& scenario, const SessionOptions& options,
                    std::string_view knownKey) {
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
  const std::string graphKey = knownKey.empty() ? graphCacheKey(scenario) : std::string(knownKey);
  const std::string found = manifest["graph_key"].get<std::string>();
  if (found != graphKey)
    throw Error(fmt::format("{}: expected graph key '{}', found '{}': the policy was made for another graph; "
                            "retrain with mgrl train {}{}",
                            (dir / "manifest.json").string(), graphKey.substr(0, 16), found.substr(0, 16),
                            options.scenario.string(), setFlags(options.sets)));
  for (const BehaviorSpec& spec : scenario.behaviors) {
    const json& entry = manifest["behaviors"].contains(spec.name) ? manifest["behaviors"][spec.name] : json();
    const json unfinished = manifest.contains("provenance") && manifest["provenance"].is_object()
                                ? manifest["provenance"].value("unfinished", json::array())
                                : json::array();
    if (entry.is_null() && unfinished.is_array() &&
        std::find(unfinished.begin(), unfinished.end(), json(spec.name)) != unfinished.end())
      throw Error(fmt::format("{}: expected a trained table for behaviour '{}', found none: its training was "
                              "interrupted; run mgrl train {}{} --resume",
                              dir.string(), spec.name, options.scenario.string(), setFlags(options.sets)));
    if (entry.is_null())
      throw Error(fmt::format("{}: expected a trained table for behaviour '{}' that the scenario asks for, found "
                              "none; run mgrl train {} --behavior {}{}",
                              dir.string(), spec.name, options.scenario.string(), spec.name, setFlags(options.sets)));
    const std::string key =
        behaviorConfigAndKey(spec, requirePlugins(options.plugins, "SessionOptions::plugins"), graphKey).second;
    if (entry.is_object() && entry.contains("key") && entry["key"].is_string() && entry["key"] != key)
      throw Error(fmt::format("{}: behaviour '{}' was trained with other settings than the scenario's now (key {} "
                              "vs {}); retrain with mgrl train {} --behavior {}{}",
                              dir.string(), spec.name, entry["key"].get<std::string>().substr(0, 16),
                              key.substr(0, 16), options.scenario.string(), spec.name, setFlags(options.sets)));
  }
}


namespace {

// A parameter value as `--set` takes it; empty for what --set cannot express.
std::string setValue(const json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number()) return value.dump();
  return {};
}

// The --set flags that give the scenario's behaviours the settings they were trained with
// in the bundle at `dir` (only for behaviours whose key differs), with a short description
// of the differences; nothing if the bundle cannot say or was made for another graph.
struct BundleSettings {
  std::vector<std::string> sets;         ///< --set texts, types first
  std::vector<std::string> differences;  ///< "hit.learner.type=value_iteration", for the message
  std::vector<std::string> replaced;     ///< "behaviors.hit.learner." blocks of another type
};

BundleSettings bundleSettings(const fs::path& dir, const Scenario& scenario, const Plugins& plugins) {
  std::vector<std::string> sets, differences, replaced;
  json manifest;
  try {
    manifest = json::parse(readFile(dir / "manifest.json"));
  } catch (const std::exception&) {
    return {};
  }
  const std::string graphKey = graphCacheKey(scenario);
  if (!manifest.is_object() || manifest.value("graph_key", json()) != json(graphKey) ||
      !manifest.contains("behaviors") || !manifest["behaviors"].is_object())
    return {};
  for (const BehaviorSpec& spec : scenario.behaviors) {
    const json& entry = manifest["behaviors"].contains(spec.name) ? manifest["behaviors"][spec.name] : json();
    if (!entry.is_object() || !entry.contains("record") || !entry["record"].is_object()) continue;
    const json trainedConfig = entry["record"].value("config", json());
    if (!trainedConfig.is_object()) continue;
    const auto [config, key] = behaviorConfigAndKey(spec, plugins, graphKey);
    if (entry.value("key", json()) == json(key)) continue;
    for (const char* block : {"discretizer", "reward", "environment", "learner"}) {
      const json trained = trainedConfig.value(block, json());
      if (!trained.is_object() || !trained.contains("type")) return {};
      const json& now = config.value(block, json::object());
      const bool newType = trained["type"] != now.value("type", json());
      if (newType) replaced.push_back(fmt::format("behaviors.{}.{}.", spec.name, block));
      for (const auto& [name, value] : trained.items()) {
        if (!newType && now.value(name, json()) == value) continue;
        const std::string text = setValue(value);
        if (text.empty()) return {};
        const std::string flag = fmt::format("behaviors.{}.{}.{}={}", spec.name, block, name, text);
        // The type first: setting it resets the block.
        if (name == "type")
          sets.insert(sets.begin(), flag);
        else
          sets.push_back(flag);
        if (name == "type" || !newType) differences.push_back(fmt::format("{}.{}.{}={}", spec.name, block, name, text));
      }
    }
  }
  return {sets, differences, replaced};
}

}  // namespace

void requireBehavior(const Scenario& scenario, const std::string& name) {
  std::vector<std::string> names;
  for (const BehaviorSpec& spec : scenario.behaviors) names.push_back(spec.name);
  if (std::find(names.begin(), names.end(), name) == names.end())
    throw Error(fmt::format("--behavior: expected one of the scenario's behaviours ({}), found {}",
                            fmt::join(names, ", "), quoteToken(name)));
}

fs::path resolvePolicy(const fs::path& policy, Scenario& scenario, const SessionOptions& options,
                       std::string* graphKey) {
  const fs::path cacheDir = options.cacheDir.empty() ? defaultCacheDirectory() : options.cacheDir;
  std::string key = graphCacheKey(scenario);
  if (policy.empty()) {
    const fs::path dir =
        defaultPolicyDirectory(cacheDir, scenario, requirePlugins(options.plugins, "SessionOptions::plugins"), key);
    precheckPolicy(dir, scenario, options, key);
    if (graphKey) *graphKey = std::move(key);
    return dir;
  }
  try {
    precheckPolicy(policy, scenario, options, key);
    if (graphKey) *graphKey = std::move(key);
    return policy;
  } catch (const Error&) {
    const std::exception_ptr refusal = std::current_exception();
    const BundleSettings adopted =
        bundleSettings(policy, scenario, requirePlugins(options.plugins, "SessionOptions::plugins"));
    if (adopted.sets.empty()) throw;
    // The user's own --set flags into a block of another type belong to the scenario's
    // plugin, not the bundle's: they go.
    SessionOptions again = options;
    std::erase_if(again.sets, [&](const std::string& set) {
      return std::any_of(adopted.replaced.begin(), adopted.replaced.end(),
                         [&](const std::string& prefix) { return set.rfind(prefix, 0) == 0; });
    });
    again.sets.insert(again.sets.end(), adopted.sets.begin(), adopted.sets.end());
    std::optional<Scenario> adjusted;
    try {
      adjusted.emplace(loadScenario(options.scenario, dataDirectory(options.dataDir), again.sets));
      checkBehaviors(*adjusted, requirePlugins(options.plugins, "SessionOptions::plugins"));
      precheckPolicy(policy, *adjusted, again);
    } catch (const Error&) {
      std::rethrow_exception(refusal);  // the bundle's settings do not fit either: the first refusal says why
    }
    if (options.log)
      options.log(fmt::format("--policy {}: using the settings the bundle was trained with ({}) instead of the "
                              "scenario's",
                              policy.string(), fmt::join(adopted.differences, ", ")));
    scenario = std::move(*adjusted);
    if (graphKey) *graphKey = graphCacheKey(scenario);
    return policy;
  }
}

std::vector<PolicyPart> policyParts(const fs::path& dir, const std::vector<Behavior>& behaviors,
                                    const GraphResult& graph, const SessionOptions& options, PolicyBundle& bundle,
                                    const std::string& skip, bool sameSettings) {
  bundle = loadPolicyBundle(dir, graph.model, graph.key);
  return policyPartsOf(bundle, dir, behaviors, options, skip, sameSettings);
}

std::vector<PolicyPart> policyPartsOf(PolicyBundle& bundle, const fs::path& dir, const std::vector<Behavior>& behaviors,
                                      const SessionOptions& options, const std::string& skip, bool sameSettings) {
  std::vector<PolicyPart> parts;
  for (const Behavior& b : behaviors) {
    if (b.name == skip) continue;
    const auto found = bundle.behaviors.find(b.name);
    if (found == bundle.behaviors.end())
      throw Error(fmt::format("{}: expected a trained table for behaviour '{}' that the scenario asks for, found "
                              "none; run mgrl train {} --behavior {}{}",
                              dir.string(), b.name, options.scenario.string(), b.name, setFlags(options.sets)));
    if (sameSettings && found->second.key != b.key)
      throw Error(fmt::format("{}: behaviour '{}' was trained with other settings than the scenario's now (key {} "
                              "vs {}); retrain with mgrl train {} --behavior {}{}",
                              dir.string(), b.name, found->second.key.substr(0, 16), b.key.substr(0, 16),
                              options.scenario.string(), b.name, setFlags(options.sets)));
    // A grid with its own structure (kd_tree refined by adaptive_value_iteration) is rebuilt
    // from the bundle's arrays; the scenario's parameters give the rest.
    PolicyBehavior& trained = found->second;
    const Discretizer* grid = b.discretizer.get();
    if (!trained.grid.empty()) {
      if (trained.gridType != b.discretizer->type())
        throw Error(fmt::format("{}: behaviour '{}' was trained on a {} grid, the scenario asks for {}; retrain with "
                                "mgrl train {} --behavior {}{}",
                                dir.string(), b.name, trained.gridType, b.discretizer->type(),
                                options.scenario.string(), b.name, setFlags(options.sets)));
      trained.restoredGrid = b.discretizer->restored(trained.grid);
      grid = trained.restoredGrid.get();
    }
    if (grid->vertexCount() != trained.table.vertexCount())
      throw Error(fmt::format("{}: behaviour '{}': expected a table over the grid's {} vertices, found {}; retrain "
                              "with mgrl train {} --behavior {}{}",
                              dir.string(), b.name, grid->vertexCount(), trained.table.vertexCount(),
                              options.scenario.string(), b.name, setFlags(options.sets)));
    parts.push_back({grid, &trained.table, b.weight, b.activation, b.stance});
  }
  return parts;
}

fs::path defaultPolicyDirectory(const fs::path& cacheDir, const Scenario& scenario, const Plugins& plugins,
                                std::string_view knownKey) {
  // Everything that trains the tables names the folder: the scenario file, its graph and
  // every behaviour's settings (after --set), so another learner gets another bundle.
  std::error_code ec;
  Hasher h;
  h.update(std::string_view("mgrl.policy-path.v2"));
  h.update(std::string_view(fs::weakly_canonical(scenario.path, ec).string()));
  const std::string graphKey = knownKey.empty() ? graphCacheKey(scenario) : std::string(knownKey);
  h.update(std::string_view(graphKey));
  for (const BehaviorSpec& spec : scenario.behaviors) {
    h.update(std::string_view(spec.name));
    h.update(std::string_view(behaviorConfigAndKey(spec, plugins, graphKey).second));
  }
  return cacheDir / "policies" / fmt::format("{}-{}", scenario.name, h.hex().substr(0, 8));
}

}  // namespace mgrl
