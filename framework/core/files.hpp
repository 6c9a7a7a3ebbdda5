#pragma once
/// \file
/// Whole files in and out: read at once with a clear error, written atomically.
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

}  // namespace mgrl
