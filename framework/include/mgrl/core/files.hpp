#pragma once
/// \file
/// Whole files in and out: read at once with a clear error, written atomically; whether a
/// folder takes new files, and which processes still own what they named after their pid.
#include <filesystem>
#include <string>
#include <string_view>

namespace mgrl {

/// Reads a whole file; throws mgrl::Error saying why it could not.
std::string readFile(const std::filesystem::path& path);

class Hasher;
/// Appends the file's contents to `hasher` exactly as `hasher.update(readFile(path))` would
/// (length, then bytes), reading it a block at a time instead of whole. Throws mgrl::Error
/// as readFile() does.
void hashFileContents(Hasher& hasher, const std::filesystem::path& path);

/// A whole file mapped read-only into memory: its bytes without copying them into a fresh
/// buffer (each fresh page costs a fault, which dominated loading a 10 MB table). The view
/// stays valid while the object lives; a file truncated meanwhile by another process may
/// end the program with SIGBUS, as any mapping would, so use it for files mgrl writes
/// whole and replaces by rename (bundles), never for files edited in place.
class MappedFile {
 public:
  /// Throws mgrl::Error saying why the file could not be opened or mapped.
  explicit MappedFile(const std::filesystem::path& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::string_view bytes() const { return {static_cast<const char*>(data_), size_}; }

 private:
  void* data_ = nullptr;
  std::size_t size_ = 0;
};

/// Writes `text` to `path` through a temporary file in the same folder and a rename, so a
/// failure never leaves a partial file. Throws mgrl::Error on failure.
void writeFileAtomically(const std::filesystem::path& path, std::string_view text);

/// True while process `pid` exists (this one included, and one owned by another user);
/// false for a pid out of range. What a writer names after its pid is stale once this is
/// false.
bool processAlive(long pid);

/// Whether `folder` takes a new file now: writes `<folder>/<probePrefix><pid>` (this
/// process's pid) and removes it again. A process killed between the two leaves its probe
/// for good, so first the probes `<probePrefix><digits>` of processes that are gone are
/// removed; those of live processes (which may be probing now) stay. False, never a throw,
/// for a folder that is missing or cannot be written: callers say what they needed it for.
bool folderTakesNewFiles(const std::filesystem::path& folder, std::string_view probePrefix);

}  // namespace mgrl
