#pragma once
/// \file
/// When the program started, for the commands that report their start-up time.

namespace mgrl::app {

/// Seconds since the program started (its static initialisation): eval and simulate
/// report it at their first decision as "startup_seconds" (with a cached graph, about
/// 0.05 s).
double secondsSinceStart();

}  // namespace mgrl::app
