#include "mgrl/core/files.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/hash.hpp"

namespace mgrl {

std::string readFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw Error(fmt::format("{}: expected a file, found a directory", path.string()));
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw Error(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  // Sized once from the file's length (a file that grows meanwhile is read to its end in
  // chunks): growing the string chunk by chunk copied a 10 MB table about twice over and
  // touched every page of each discarded buffer, and slowed every command's start.
  std::string text;
  std::error_code sizeError;
  const std::uintmax_t expected = std::filesystem::file_size(path, sizeError);
  if (!sizeError && expected > 0 && expected < (std::uintmax_t{1} << 40)) {
    text.resize(static_cast<std::size_t>(expected));
    text.resize(std::fread(text.data(), 1, text.size(), file));
  }
  char chunk[1 << 16];
  std::size_t got = 0;
  while ((got = std::fread(chunk, 1, sizeof chunk, file)) > 0) text.append(chunk, got);
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) throw Error(fmt::format("{}: cannot read", path.string()));
  return text;
}

void hashFileContents(Hasher& hasher, const std::filesystem::path& path) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || std::filesystem::is_directory(path, ec)) {
    hasher.update(std::string_view(readFile(path)));  // says why, or copes with a special file
    return;
  }
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw Error(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  // The length goes first, so a file that changes size while it is read is hashed again whole.
  Hasher streamed = hasher;
  streamed.update(static_cast<std::int64_t>(size));
  // 64 KB, uninitialised: small enough to come from the heap and stay in cache (a fresh
  // zeroed megabyte was a new mapping per file, 256 page faults, most of eval's hashing).
  constexpr std::size_t kBlock = std::size_t{1} << 16;
  const auto block = std::make_unique_for_overwrite<char[]>(kBlock);
  std::uintmax_t total = 0;
  std::size_t got = 0;
  while ((got = std::fread(block.get(), 1, kBlock, file)) > 0) {
    streamed.updateBytes(std::string_view(block.get(), got));
    total += got;
  }
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) throw Error(fmt::format("{}: cannot read", path.string()));
  if (total != size) {
    hasher.update(std::string_view(readFile(path)));
    return;
  }
  hasher = streamed;
}

MappedFile::MappedFile(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    const int error = errno;
    ::close(fd);
    throw Error(fmt::format("{}: cannot read: {}", path.string(), std::strerror(error)));
  }
  if (!S_ISREG(info.st_mode)) {
    ::close(fd);
    throw Error(fmt::format("{}: expected a regular file, found {}", path.string(),
                            S_ISDIR(info.st_mode) ? "a directory" : "a device, pipe or socket"));
  }
  size_ = static_cast<std::size_t>(info.st_size);
  if (size_ > 0) {
    // Populated at once: one call faults the whole file in from the page cache.
    data_ = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    if (data_ == MAP_FAILED) {
      const int error = errno;
      ::close(fd);
      data_ = nullptr;
      throw Error(fmt::format("{}: cannot map: {}", path.string(), std::strerror(error)));
    }
  }
  ::close(fd);
}

MappedFile::~MappedFile() {
  if (data_) ::munmap(data_, size_);
}

void writeFileAtomically(const std::filesystem::path& path, std::string_view text) {
  const std::filesystem::path folder = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  std::random_device device;
  const std::filesystem::path temporary =
      folder / fmt::format(".{}.tmp-{:08x}", path.filename().string(), device());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(errno)));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw Error(fmt::format("{}: cannot write (disk full?)", path.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw Error(fmt::format("{}: cannot write: {}", path.string(), ec.message()));
  }
}

bool processAlive(long pid) {
  if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return false;
  // EPERM: it exists, owned by someone else.
  return pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

bool folderTakesNewFiles(const std::filesystem::path& folder, std::string_view probePrefix) {
  namespace fs = std::filesystem;
  // Found by the kill tests: a process killed between writing its probe and removing it (a
  // few microseconds, but forever after) left the file behind.
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const std::size_t digits = name.size() - std::min(name.size(), probePrefix.size());
    if (digits == 0 || digits > 10 || name.compare(0, probePrefix.size(), probePrefix) != 0 ||
        name.find_first_not_of("0123456789", probePrefix.size()) != std::string::npos)
      continue;
    if (processAlive(std::stol(name.substr(probePrefix.size())))) continue;
    std::error_code ignored;
    fs::remove(it->path(), ignored);
  }
  const fs::path probe = folder / fmt::format("{}{}", probePrefix, ::getpid());
  bool written = false;
  {
    std::ofstream file(probe);
    written = file && (file << "x") && file.flush();
  }
  fs::remove(probe, ec);
  return written;
}

}  // namespace mgrl
