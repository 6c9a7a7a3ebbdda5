#pragma once
/// \file
/// The built-in plug-ins: every discretizer, reward, environment model, learner and
/// controller that ships with mgrl, registered once (DESIGN.md sec. 4). This library is the
/// composition root: the one place above both the framework and the plug-in folders that
/// names the folders. The front ends (the command line, the viewer, the Python module, the
/// benchmarks) hand its registries to the session stage through SessionOptions::plugins.
#include "mgrl/session/plugins.hpp"

namespace mgrl {

/// Adds every built-in plug-in to `plugins`: a program that adds plug-ins of its own
/// starts from an empty Plugins, calls this, then adds them.
void registerBuiltins(Plugins& plugins);

/// The registries with every built-in plug-in (built on first use, then shared).
const Plugins& builtinPlugins();

}  // namespace mgrl
