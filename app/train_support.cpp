#include "train_support.hpp"

#include "mgrl/core/files.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;

// A second Ctrl-C kills at once (SA_RESETHAND in StopSignals).
std::atomic<bool> stopRequested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onStopSignal(int) { stopRequested.store(true); }

fs::path checkpointDirectory(const fs::path& out, const std::string& behavior) {
  return out.parent_path() / (out.filename().string() + ".checkpoints") / behavior;
}

void removeCheckpoint(const fs::path& dir) {
  std::error_code ec;
  for (const StaleSibling& stale : staleSiblings(dir)) fs::remove_all(stale.path, ec);
  fs::remove_all(dir, ec);
  fs::remove(dir.parent_path(), ec);  // only if empty
}

}  // namespace mgrl::app
