#pragma once
/// \file
/// `mgrl train`'s Ctrl-C: the flag training watches (TrainHooks::stop) and the signal
/// handlers that raise it while a command trains.
#include <atomic>
#include <csignal>

namespace mgrl::app {

/// Ctrl-C and SIGTERM while training raise this flag (StopSignals): the learner stops at
/// its next safe point and saves a checkpoint; what had finished is kept.
extern std::atomic<bool> stopRequested;
extern "C" void onStopSignal(int);

/// Installs the handlers for its lifetime (a second Ctrl-C kills at once) and lowers the flag.
class StopSignals {
 public:
  StopSignals() {
    stopRequested.store(false);
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &oldInt_);
    sigaction(SIGTERM, &action, &oldTerm_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &oldInt_, nullptr);
    sigaction(SIGTERM, &oldTerm_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction oldInt_ {
  }, oldTerm_{};
};

}  // namespace mgrl::app
