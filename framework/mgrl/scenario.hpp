#pragma once
/// \file
/// A scenario: a YAML file naming the motion a graph is built from and how (`motion:` and
/// `graph:` sections; scenarios/README.md documents every key). Paths resolve against the
/// scenario's folder, then the data folder (DESIGN.md sec. 6).
#include <filesystem>
#include <string>

#include "mgrl/config.hpp"
#include "mgrl/graph_params.hpp"
#include "mgrl/motion_database.hpp"

namespace mgrl {

struct Scenario {
  std::filesystem::path path;  ///< the YAML file
  std::string name;            ///< `name:`, or the file's stem
  std::string description;
  MotionSpec motion;           ///< files resolved and expanded (globs), in order
  GraphParams graph;
  ConfigNode root;             ///< the whole document, for sections read elsewhere
};

/// Parses and validates a scenario. `dataDir` resolves motion paths that are not found
/// beside the scenario. Throws ConfigError (`file:line:col: key.path: problem`) for any
/// unknown key, wrong type or out-of-range value, a missing section, or a motion path or
/// pattern that matches no file.
Scenario loadScenario(const std::filesystem::path& path, const std::filesystem::path& dataDir);
/// The same from YAML text; `source` names it in messages and its folder anchors relative paths.
Scenario parseScenario(std::string_view text, const std::filesystem::path& source,
                       const std::filesystem::path& dataDir);

/// Hex key of everything a graph depends on: the bytes of every motion (and ASF) file, the
/// motion and graph parameters (not the thread count) and the graph format version. Equal
/// keys mean the cached graph can be reused.
std::string graphCacheKey(const Scenario& scenario);

}  // namespace mgrl
