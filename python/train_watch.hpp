#pragma once
// A C++ learner trained from Python: progress and snapshots relayed to Python callbacks,
// Ctrl-C turned into the learner's stop request (train_watch.cpp).
#include <cstddef>
#include <string>

#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/problem.hpp"
#include "support.hpp"

namespace mgrl::python {

/// Tabulates `problem` and trains `learner` on it on a worker thread while this thread
/// (holding the GIL between waits) relays progress (`progress(dict)`, about ten times a
/// second) and `snapshots` tables (`onSnapshot(dict)`), and watches for Ctrl-C. Throws
/// KeyboardInterrupt (Python's) when interrupted, a callback's exception if it raised.
TrainResult trainWatched(const std::string& behavior, const Learner& learner, const Problem& problem,
                         const py::object& progress, std::size_t snapshots = 0,
                         const py::object& onSnapshot = py::none());

}  // namespace mgrl::python
