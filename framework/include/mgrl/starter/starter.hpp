#pragma once
/// \file
/// What `mgrl init FILE... [--out SCENARIO]` does: inspects motion files and writes a
/// commented starter scenario for them. It loads and annotates the capture as `graph`
/// would, tries graph settings until the largest component keeps most frames, sizes the
/// grids to the capture's travel and hitting points, and picks behaviours the capture can
/// do (approach and hit where it punches, kick where it only kicks, walking to a goal
/// otherwise), with learners that train in about a minute. The file is written only once
/// it loads as a scenario.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/motion/roles.hpp"
#include "mgrl/motion/units.hpp"
#include "mgrl/session/plugins.hpp"

namespace mgrl {

struct InitOptions {
  std::vector<std::filesystem::path> files;  ///< motion files, as the user named them
  std::filesystem::path out;                 ///< the scenario to write; empty: NAME.yaml here
  std::string name;                          ///< scenario name; empty: from the first file
  std::filesystem::path dataDir;             ///< for paths relative to the data folder
  LengthUnit units = LengthUnit::Auto;
  double fps = 30;
  RoleOverrides roles;
  bool force = false;  ///< replace an existing file
  std::function<void(const std::string&)> log;
  /// The registries the written scenario's behaviours are checked against. Required.
  const Plugins* plugins = nullptr;
};

/// Writes the scenario and returns what was found and chosen (see initText()). Throws
/// mgrl::Error, leaving nothing behind, when a file cannot be read, the files do not share
/// a skeleton, the output exists without `force`, or no graph setting keeps a usable graph.
nlohmann::json runInit(const InitOptions& options);
std::string initText(const nlohmann::json& report);

}  // namespace mgrl
