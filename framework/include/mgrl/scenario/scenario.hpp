#pragma once
/// \file
/// A scenario: a YAML file naming the motion a graph is built from and how (`motion:` and
/// `graph:` sections; scenarios/README.md documents every key). Paths resolve against the
/// scenario's folder, then the data folder (DESIGN.md sec. 6).
#include <filesystem>
#include <string>
#include <vector>

#include "mgrl/core/config.hpp"
#include "mgrl/graph/graph_params.hpp"
#include "mgrl/learning/behavior_spec.hpp"
#include "mgrl/motion/motion_database.hpp"

namespace mgrl {

struct Scenario {
  std::filesystem::path path;  ///< the YAML file
  std::string name;            ///< `name:`, or the file's stem
  std::string description;
  MotionSpec motion;  ///< files resolved and expanded (globs), in order
  GraphParams graph;
  std::vector<BehaviorSpec> behaviors;  ///< `behaviors:` in document order (may be empty)
  ConfigNode root;                      ///< the whole document, for sections read elsewhere
  /// `sparring_scenario:` resolved against this file's folder: the scenario whose
  /// behaviours the viewer's sparring and crowd modes play; "" none.
  std::filesystem::path sparringScenario = {};
};

/// Parses and validates a scenario. `dataDir` resolves motion paths that are not found
/// beside the scenario. Throws ConfigError (`file:line:col: key.path: problem`) for any
/// unknown key, wrong type or out-of-range value, a missing section, or a motion path or
/// pattern that matches no file.
///
/// `overrides` are `KEY=VALUE` texts (`--set`, DESIGN.md sec. 5) applied to the document
/// before it is checked: KEY is a dotted path (`behaviors.hit.learner.budget`), created if
/// missing, whose parts may end in list indices naming elements the file has
/// (`behaviors.keep.reward.terms[1].weight`); VALUE is a scalar (a number, a word,
/// true/false). Setting a `type` to another
/// plugin drops the block's other keys from the file (they were the old plugin's
/// parameters). A malformed override is a ConfigError naming it.
Scenario loadScenario(const std::filesystem::path& path, const std::filesystem::path& dataDir,
                      const std::vector<std::string>& overrides = {});
/// Throws ConfigError (at the key) unless `sparring_scenario:` is absent or names an
/// existing file other than the scenario itself; what opens it (`mgrl serve`) calls this.
void checkSparringScenario(const Scenario& scenario);
/// Throws ConfigError (at the key) unless `sparring_scenario:` is absent or names an
/// existing file other than the scenario itself; what opens it (`mgrl serve`) calls this.
void checkSparringScenario(const Scenario& scenario);
/// The same from YAML text; `source` names it in messages and its folder anchors relative paths.
Scenario parseScenario(std::string_view text, const std::filesystem::path& source, const std::filesystem::path& dataDir,
                       const std::vector<std::string>& overrides = {});

/// Hex key of everything a graph depends on: the bytes of every motion (and ASF) file, the
/// motion and graph parameters (not the thread count) and the graph format version. Equal
/// keys mean the cached graph can be reused.
std::string graphCacheKey(const Scenario& scenario);

}  // namespace mgrl
