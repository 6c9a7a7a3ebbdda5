#include "mgrl/core/bundle.hpp"

#include <stdio.h>  // renameat2
#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <system_error>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/files.hpp"

namespace mgrl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void renameOrThrow(const fs::path& from, const fs::path& to, std::string_view source) {
  std::error_code ec;
  fs::rename(from, to, ec);
  if (ec) throw Error(fmt::format("{}: cannot rename {} to {}: {}", source, from.string(), to.string(), ec.message()));
}

// Swaps `from` and `to` in one step (both must exist), so that `to` is never missing.
// False if the file system cannot (the caller falls back to two renames).
bool exchange(const fs::path& from, const fs::path& to, std::error_code& ec) {
  ec.clear();
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_EXCHANGE) == 0) return true;
  ec = std::error_code(errno, std::generic_category());
  return false;
}

std::string dumpForMessage(const json& value) {
  return value.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Writing

void writeWholeFile(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (out) out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (out) out.flush();
  if (!out) throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(errno)));
}

fs::path freshSibling(const fs::path& dir, std::string_view tag, bool create) {
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0; attempt < 1000; ++attempt) {
    const fs::path candidate =
        dir.parent_path() / fmt::format("{}.{}-{}-{}", dir.filename().string(), tag, ::getpid(), counter++);
    std::error_code ec;
    if (create) {
      if (fs::create_directory(candidate, ec)) return candidate;
      if (ec) throw Error(fmt::format("{}: cannot create {}: {}", dir.string(), candidate.string(), ec.message()));
    } else if (!fs::exists(fs::symlink_status(candidate, ec))) {
      return candidate;
    }
  }
  throw Error(fmt::format("{}: expected a free name for a {} directory beside it, found none", dir.string(), tag));
}

std::vector<StaleSibling> staleSiblings(const fs::path& dirArgument) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  std::vector<StaleSibling> found;
  const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
  const std::string stem = dir.filename().string();
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    // <stem>.<tag>-<pid>-<counter>, as freshSibling() names them.
    if (name.size() <= stem.size() + 1 || name.compare(0, stem.size(), stem) != 0 || name[stem.size()] != '.') continue;
    const std::string_view rest = std::string_view(name).substr(stem.size() + 1);
    std::string_view tag;
    if (rest.rfind("tmp-", 0) == 0 || rest.rfind("old-", 0) == 0) tag = rest.substr(0, 3);
    else continue;
    const std::string_view numbers = rest.substr(4);
    const std::size_t dash = numbers.find('-');
    if (dash == 0 || dash == std::string_view::npos || dash > 12 || dash + 1 == numbers.size() ||
        numbers.find_first_not_of("0123456789-") != std::string_view::npos ||
        numbers.find('-', dash + 1) != std::string_view::npos)
      continue;
    const long pid = std::stol(std::string(numbers.substr(0, dash)));
    if (processAlive(pid)) continue;
    found.push_back({it->path(), std::string(tag)});
  }
  std::sort(found.begin(), found.end(), [](const StaleSibling& a, const StaleSibling& b) { return a.path < b.path; });
  return found;
}

void recoverBundleDirectory(const fs::path& dirArgument, std::string_view manifestName, const WarningSink& log) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  std::vector<StaleSibling> stale = staleSiblings(dir);
  if (stale.empty()) return;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(dir, ec))) {
    // A writer died between its renames: put back the newest complete bundle, a finished
    // temporary (it has its manifest, written last) before a replaced old one.
    for (const char* tag : {"tmp", "old"})
      for (const StaleSibling& s : stale)
        if (s.tag == tag && fs::exists(s.path / manifestName, ec) && !fs::exists(fs::symlink_status(dir, ec))) {
          fs::rename(s.path, dir, ec);
          if (!ec && log) log(fmt::format("{}: recovered the bundle a killed process left in {}", dir.string(), s.path.filename().string()));
        }
  }
  for (const StaleSibling& s : stale) {
    if (!fs::exists(fs::symlink_status(s.path, ec))) continue;  // recovered above
    const auto removed = fs::remove_all(s.path, ec);
    if (!ec && removed > 0 && log)
      log(fmt::format("{}: removed {}, left by a process that is gone", dir.string(), s.path.filename().string()));
  }
}

bool isPlainFileName(std::string_view name) {
  return !name.empty() && name != "." && name != ".." && name.find_first_of(std::string_view("/\\\0", 3)) == name.npos;
}

bool BundleWriter::replaceable(const fs::path& dir) const {
  if (replaceable_) return replaceable_(dir);
  std::error_code ec;
  return fs::exists(dir / manifestName_, ec) || fs::is_empty(dir, ec);
}

BundleWriter::BundleWriter(const fs::path& dirArgument, std::string_view kind, std::string_view manifestName,
                           Replaceable replaceable)
    // "cache/graph/" names the same bundle as "cache/graph".
    : dir_(dirArgument.has_filename() ? dirArgument : dirArgument.parent_path()),
      kind_(kind),
      manifestName_(manifestName),
      replaceable_(std::move(replaceable)) {
  const std::string source = dir_.string();
  recoverBundleDirectory(dir_, manifestName_);
  // Never delete something that is not ours to replace.
  std::error_code ec;
  const fs::file_status existing = fs::symlink_status(dir_, ec);
  if (fs::exists(existing)) {
    if (!fs::is_directory(existing))
      throw Error(fmt::format("{}: expected a {} directory or nothing, found another kind of file", source, kind_));
    if (!this->replaceable(dir_))
      throw Error(fmt::format("{}: expected a {} (with {}) or an empty directory to replace, "
                              "found a directory with other files; not deleting it",
                              source, kind_, manifestName_));
  }
  if (dir_.has_parent_path()) {
    fs::create_directories(dir_.parent_path(), ec);
    if (ec) throw Error(fmt::format("{}: cannot create {}: {}", source, dir_.parent_path().string(), ec.message()));
  }
  temporary_ = freshSibling(dir_, "tmp", true);
}

BundleWriter::~BundleWriter() {
  if (committed_) return;
  std::error_code ignored;
  fs::remove_all(temporary_, ignored);
}

void BundleWriter::commit(std::string_view manifestText) {
  const std::string source = dir_.string();
  committed_ = true;  // whatever happens below, the temporary is dealt with here
  try {
    // Last, so a directory with a manifest has all its files.
    writeWholeFile(temporary_ / manifestName_, manifestText);
    // The destination is never missing (an existing bundle is
    // swapped with the new one in one step), and another process writing the same bundle
    // at the same time makes neither fail: the last swap wins, each is complete.
    for (int attempt = 0;; ++attempt) {
      std::error_code renamed, ec;
      fs::rename(temporary_, dir_, renamed);  // onto nothing or an empty directory
      if (!renamed) return;
      if (renamed != std::errc::directory_not_empty && renamed != std::errc::file_exists)
        throw Error(fmt::format("{}: cannot rename {} to {}: {}", source, temporary_.string(), dir_.string(),
                                renamed.message()));
      if (!fs::is_directory(fs::symlink_status(dir_, ec)) || !replaceable(dir_))
        throw Error(fmt::format("{}: expected a {} (with {}) or an empty directory to replace, "
                                "found a directory with other files; not deleting it",
                                source, kind_, manifestName_));
      std::error_code swapped;
      if (exchange(temporary_, dir_, swapped)) break;  // `temporary_` now holds the old bundle
      if (swapped == std::errc::no_such_file_or_directory && attempt < 100) continue;  // it went meanwhile
      if (swapped != std::errc::invalid_argument && swapped != std::errc::operation_not_supported)
        throw Error(fmt::format("{}: cannot swap {} with {}: {}", source, temporary_.string(), dir_.string(),
                                swapped.message()));
      // A file system without atomic exchange: rename the old one aside first.
      const fs::path old = freshSibling(dir_, "old", false);
      renameOrThrow(dir_, old, source);
      try {
        renameOrThrow(temporary_, dir_, source);
      } catch (const Error&) {
        std::error_code ignored;
        fs::rename(old, dir_, ignored);  // put the previous bundle back
        throw;
      }
      std::error_code ignored;
      fs::remove_all(old, ignored);
      return;
    }
    // The new bundle is in place; an old copy that cannot be removed only wastes space.
    std::error_code ignored;
    fs::remove_all(temporary_, ignored);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(temporary_, ignored);
    throw;
  }
}

void writeBundleDirectory(const fs::path& dirArgument, const std::vector<BundleFile>& files,
                          std::string_view manifestText, std::string_view kind, std::string_view manifestName) {
  const fs::path dir = dirArgument.has_filename() ? dirArgument : dirArgument.parent_path();
  for (const BundleFile& file : files)
    if (!isPlainFileName(file.name) || file.name == manifestName)
      throw Error(fmt::format("{}: expected plain file names in a {} other than {}, found {}", dir.string(), kind,
                              manifestName, quoteToken(file.name)));
  BundleWriter writer(dir, kind, manifestName);
  for (const BundleFile& file : files) writeWholeFile(writer.path() / file.name, file.bytes);
  writer.commit(manifestText);
}

std::string quoteKey(std::string_view key) { return quoteToken(key.substr(0, 16)); }

std::string formatShape(const std::vector<std::size_t>& shape) {
  if (shape.size() == 1) return fmt::format("({},)", shape[0]);
  return fmt::format("({})", fmt::join(shape, ", "));
}

json bundleArrayEntry(const BundleFile& file, std::string_view dtype, const std::vector<std::size_t>& shape) {
  return {{"file", file.name},
          {"dtype", std::string(dtype)},
          {"shape", shape},
          {"bytes", file.bytes.size()},
          {"hash", hexDigest(hashBytes(file.bytes))}};
}

// ---------------------------------------------------------------------------------------
// Reading

void ManifestReader::fail(std::string_view path, std::string_view expected, const json& found) const {
  throw Error(fmt::format("{}: {}: expected {}, found {}", source_, path, expected, quoteToken(dumpForMessage(found))));
}

const json& ManifestReader::member(const json& parent, std::string_view path, std::string_view key) const {
  const auto it = parent.find(key);
  if (it == parent.end())
    throw Error(
        fmt::format("{}: {}: expected the key '{}', found none", source_, path.empty() ? "manifest" : path, key));
  return *it;
}

const json& ManifestReader::object(const json& parent, std::string_view path, std::string_view key,
                                   std::initializer_list<std::string_view> allowed) const {
  const json& value = member(parent, path, key);
  const std::string here = join(path, key);
  if (!value.is_object()) fail(here, "an object", value);
  if (allowed.size() == 0) return value;
  for (const auto& item : value.items()) {
    bool known = false;
    for (std::string_view name : allowed) known = known || item.key() == name;
    if (!known)
      throw Error(fmt::format("{}: {}: expected only the keys {}, found '{}'", source_, here, fmt::join(allowed, ", "),
                              item.key()));
  }
  return value;
}

std::string ManifestReader::string(const json& parent, std::string_view path, std::string_view key) const {
  const json& value = member(parent, path, key);
  if (!value.is_string()) fail(join(path, key), "a string", value);
  return value.get<std::string>();
}

double ManifestReader::number(const json& parent, std::string_view path, std::string_view key) const {
  const json& value = member(parent, path, key);
  if (!value.is_number()) fail(join(path, key), "a number", value);
  return value.get<double>();
}

std::uint64_t ManifestReader::unsignedInteger(const json& parent, std::string_view path, std::string_view key,
                                              std::uint64_t max) const {
  const json& value = member(parent, path, key);
  if (!value.is_number_unsigned() || value.get<std::uint64_t>() > max)
    fail(join(path, key), fmt::format("an integer in [0, {}]", max), value);
  return value.get<std::uint64_t>();
}

std::string ManifestReader::join(std::string_view path, std::string_view key) {
  return path.empty() ? std::string(key) : fmt::format("{}.{}", path, key);
}

json readManifestObject(const fs::path& path) {
  const ManifestReader reader(path.string());
  json manifest;
  try {
    manifest = json::parse(readFile(path));
  } catch (const json::parse_error& e) {
    throw Error(fmt::format("{}: expected JSON, found a syntax error ({})", reader.source(), e.what()));
  }
  if (!manifest.is_object()) reader.fail("manifest", "a JSON object", manifest);
  return manifest;
}

std::string manifestHash(const json& manifest) {
  json members = manifest;
  if (members.is_object()) members.erase("hash");
  return hexDigest(hashBytes(members.dump()));
}

void checkManifestHash(const json& manifest, const ManifestReader& reader) {
  const std::string stored = reader.string(manifest, "", "hash");
  std::string actual;
  try {
    actual = manifestHash(manifest);
  } catch (const json::exception& e) {
    throw Error(fmt::format("{}: expected valid UTF-8 strings, found {}", reader.source(), e.what()));
  }
  if (actual != stored)
    throw Error(fmt::format("{}: expected its members to hash to {} as its \"hash\" says, found {} (the file was "
                            "altered)",
                            reader.source(), quoteToken(stored), quoteToken(actual)));
}

template <NpyElement T>
MappedBundleArray<T> mapBundleArray(const fs::path& dir, const ManifestReader& reader, const json& parent,
                                    std::string_view parentPath, std::string_view key, std::string_view expectedFile) {
  const json& entry = reader.object(parent, parentPath, key, {"file", "dtype", "shape", "bytes", "hash"});
  const std::string path = ManifestReader::join(parentPath, key);
  const std::string file = reader.string(entry, path, "file");
  if (!expectedFile.empty() && file != expectedFile)
    reader.fail(ManifestReader::join(path, "file"), fmt::format("'{}'", expectedFile), entry["file"]);
  // Whatever the manifest says, never read outside the bundle.
  if (!isPlainFileName(file))
    reader.fail(ManifestReader::join(path, "file"), "a file name inside the bundle (no '/', '\\' or '..')",
                entry["file"]);
  if (reader.string(entry, path, "dtype") != npyDescr<T>())
    reader.fail(ManifestReader::join(path, "dtype"), fmt::format("'{}'", npyDescr<T>()), entry["dtype"]);
  const json& shapeJson = reader.member(entry, path, "shape");
  std::vector<std::size_t> shape;
  if (!shapeJson.is_array()) reader.fail(ManifestReader::join(path, "shape"), "an array of dimensions", shapeJson);
  for (const json& d : shapeJson) {
    if (!d.is_number_unsigned()) reader.fail(ManifestReader::join(path, "shape"), "non-negative integers", shapeJson);
    shape.push_back(d.get<std::size_t>());
  }
  const std::uint64_t bytes = reader.unsignedInteger(entry, path, "bytes", std::numeric_limits<std::uint64_t>::max());
  const std::string hash = reader.string(entry, path, "hash");

  const std::string manifestName = fs::path(reader.source()).filename().string();
  const fs::path filePath = dir / file;
  const std::string source = filePath.string();
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(filePath, ec);
  if (ec)
    throw Error(fmt::format("{}: expected the file listed in {}, found none ({})", source, manifestName, ec.message()));
  // Before reading, so a huge stray file is refused without loading it.
  if (size != bytes)
    throw Error(fmt::format("{}: expected {} bytes as in {}, found {}", source, bytes, manifestName, size));
  MappedBundleArray<T> array;
  array.file = std::make_unique<MappedFile>(filePath);
  const std::string_view text = array.file->bytes();
  if (text.size() != bytes)
    throw Error(fmt::format("{}: expected {} bytes as in {}, found {}", source, bytes, manifestName, text.size()));
  const std::string actualHash = hexDigest(hashBytes(text));
  if (actualHash != hash)
    throw Error(fmt::format("{}: expected hash {} as in {}, found {} (the file was altered)", source,
                            quoteToken(hash), manifestName, quoteToken(actualHash)));
  std::vector<std::size_t> fileShape;
  if (const std::optional<std::span<const T>> view = npyView<T>(text, source, &fileShape)) {
    array.data = *view;
  } else {
    array.copy = npyDecode<T>(text, source, &fileShape);
    array.data = array.copy;
  }
  if (fileShape != shape)
    throw Error(fmt::format("{}: expected shape {} as in {}, found {}", source, formatShape(shape), manifestName,
                            formatShape(fileShape)));
  array.shape = std::move(fileShape);
  return array;
}

template <NpyElement T>
std::vector<T> loadBundleArray(const fs::path& dir, const ManifestReader& reader, const json& parent,
                               std::string_view parentPath, std::string_view key, std::string_view expectedFile,
                               std::vector<std::size_t>* shapeOut) {
  MappedBundleArray<T> array = mapBundleArray<T>(dir, reader, parent, parentPath, key, expectedFile);
  std::vector<T> data = array.copy.empty() ? std::vector<T>(array.data.begin(), array.data.end()) : std::move(array.copy);
  if (shapeOut) *shapeOut = std::move(array.shape);
  return data;
}

#define MGRL_BUNDLE_INSTANTIATE(T)                                                                             \
  template std::vector<T> loadBundleArray<T>(const fs::path&, const ManifestReader&, const json&,               \
                                             std::string_view, std::string_view, std::string_view,              \
                                             std::vector<std::size_t>*);                                        \
  template MappedBundleArray<T> mapBundleArray<T>(const fs::path&, const ManifestReader&, const json&,          \
                                                  std::string_view, std::string_view, std::string_view);
MGRL_BUNDLE_INSTANTIATE(std::uint8_t)
MGRL_BUNDLE_INSTANTIATE(std::uint32_t)
MGRL_BUNDLE_INSTANTIATE(std::int32_t)
MGRL_BUNDLE_INSTANTIATE(float)
MGRL_BUNDLE_INSTANTIATE(double)
#undef MGRL_BUNDLE_INSTANTIATE

}  // namespace mgrl
