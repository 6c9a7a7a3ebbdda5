#pragma once
/// \file
/// The composition root's plugin list: every discretizer, reward, environment model,
/// learner and controller the application offers, registered explicitly (DESIGN.md sec. 4).
#include <string>

#include "builtin_plugins.hpp"
#include "mgrl/session/plugins.hpp"

namespace mgrl::app {

/// The registries with every built-in plugin (mgrl::builtinPlugins(), the session stage's).
inline const Plugins& plugins() { return builtinPlugins(); }

/// `mgrl list`: every registered name with its summary and parameters (default, range and
/// unit, help), seam by seam.
std::string listText(const Plugins& plugins);
nlohmann::json listJson(const Plugins& plugins);

}  // namespace mgrl::app
