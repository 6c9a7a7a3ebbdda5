#pragma once
/// \file
/// Every registry a session works with: the behaviours' plug-ins (learning stage) and the
/// controllers (runtime seam). The composition root fills them (app/builtins: the built-in
/// plug-ins) and hands them to the session stage through SessionOptions::plugins.
#include "mgrl/learning/behavior.hpp"
#include "mgrl/session/controllers.hpp"

namespace mgrl {

/// The behaviours' registries and the controllers'. A behaviour's plug-ins are built in the
/// learning stage, below the controllers (runtime), so that stage takes BehaviorPlugins
/// and a Plugins is passed to it as one.
struct Plugins : BehaviorPlugins {
  ControllerRegistry controllers;
};

}  // namespace mgrl
