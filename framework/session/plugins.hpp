#pragma once
/// \file
/// The built-in plug-ins: every discretizer, reward, environment model and learner that
/// ships with mgrl, registered once (DESIGN.md sec. 4). The session stage is the
/// composition root: the only framework code that names the plug-in folders.
#include "mgrl/learning/behavior.hpp"

namespace mgrl {

/// The registries with every built-in plug-in (built on first use, then shared).
const Plugins& builtinPlugins();

}  // namespace mgrl
