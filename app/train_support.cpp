#include "train_support.hpp"

namespace mgrl::app {

// A second Ctrl-C kills at once (SA_RESETHAND in StopSignals).
std::atomic<bool> stopRequested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onStopSignal(int) { stopRequested.store(true); }

}  // namespace mgrl::app
