#pragma once
// Training from Python: progress and snapshots relayed to Python callbacks, Ctrl-C turned
// into the learner's stop request (train_watch.cpp).
#include <cstddef>
#include <string>

#include "mgrl/session/training.hpp"
#include "support.hpp"

namespace mgrl::python {

/// Trains `settings.behavior` of `session` (trainScenario) on a worker thread while this
/// thread (holding the GIL between waits) relays progress (`progress(dict)`, about ten times
/// a second), `snapshots` tables (`onSnapshot(dict)`) and what training says (to Python's
/// stderr), and watches for Ctrl-C. Throws KeyboardInterrupt (Python's) when interrupted, a
/// callback's exception if it raised.
Trained trainWatched(const Session& session, const TrainSettings& settings, const py::object& progress,
                     std::size_t snapshots = 0, const py::object& onSnapshot = py::none());

}  // namespace mgrl::python
