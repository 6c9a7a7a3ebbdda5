#pragma once
/// \file
/// Bundles (DESIGN.md sec. 6): a directory holding a JSON manifest and NumPy .npy files,
/// written all at once so a crash never leaves half of one. The graph cache, policy bundles
/// and training checkpoints are bundles; this header is what they share:
/// - writing: writeBundleDirectory() puts the files in a temporary sibling directory, the
///   manifest last, and renames it onto the destination;
/// - the manifest entry of an array, `{"file": "q.npy", "dtype": "<f4", "shape": [A, V],
///   "bytes": size, "hash": "<xxh64 hex>"}` (bundleArrayEntry(), encodeBundleArray());
/// - reading: ManifestReader checks the type of every manifest member it reads, and
///   loadBundleArray() checks one array file against its entry before decoding it;
/// - sealing: manifestHash() and checkManifestHash() cover the manifest's own values.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/npy.hpp"

namespace mgrl {

/// One file of a bundle: its name inside the directory and its whole contents.
struct BundleFile {
  std::string name;
  std::string bytes;
};

/// Writes `files` and then `manifestText` (as `manifestName`) into a fresh temporary
/// directory beside `dir` and renames it onto `dir`, so a crash leaves either a whole
/// bundle at `dir` or none. A trailing '/' in `dir` is ignored;
/// `dir`'s parent is created if needed. `kind` names the bundle in messages ("graph
/// bundle", "policy bundle"). An existing bundle is swapped with the new one in one step
/// (renameat2 RENAME_EXCHANGE), so `dir` is never missing; another process writing the
/// same `dir` at the same time makes neither fail (the last one wins). Leftovers of killed
/// writers are cleaned first (recoverBundleDirectory()).
/// Throws mgrl::Error, leaving no temporary directory, if a file name is not a plain name
/// (isPlainFileName()), if `dir` is something other than a directory holding
/// `manifestName` or an empty directory (it is never deleted then), or on any I/O failure.
void writeBundleDirectory(const std::filesystem::path& dir, const std::vector<BundleFile>& files,
                          std::string_view manifestText, std::string_view kind,
                          std::string_view manifestName = "manifest.json");

/// A bundle written in steps, for files too large to hold in memory at once (writeBundleDirectory()
/// is this class with files given as strings). The constructor does everything that can
/// fail before the work that fills the bundle: it cleans the leftovers of killed writers
/// (recoverBundleDirectory()), checks that `dir` may be replaced, creates `dir`'s parent
/// and a fresh temporary directory beside `dir` (freshSibling()); the caller writes files
/// into path(); commit() writes the manifest last and swaps the temporary onto `dir` as
/// writeBundleDirectory() says, so `dir` always holds a whole bundle, old or new, and is
/// never missing once it existed. Destroyed uncommitted, it removes the temporary.
class BundleWriter {
 public:
  /// Which existing directories may be replaced; by default (none given) an empty one or
  /// one holding `manifestName`.
  using Replaceable = std::function<bool(const std::filesystem::path&)>;

  /// Throws mgrl::Error, leaving no temporary, if `dir` is something other than a
  /// directory that may be replaced (it is never deleted then), or if the parent or the
  /// temporary cannot be created.
  BundleWriter(const std::filesystem::path& dir, std::string_view kind, std::string_view manifestName = "manifest.json",
               Replaceable replaceable = {});
  ~BundleWriter();
  BundleWriter(const BundleWriter&) = delete;
  BundleWriter& operator=(const BundleWriter&) = delete;

  /// The temporary directory to write the bundle's files into (plain names, not the
  /// manifest's).
  const std::filesystem::path& path() const { return temporary_; }
  /// The destination.
  const std::filesystem::path& destination() const { return dir_; }

  /// Writes `manifestText` as the manifest and puts the bundle in place. Throws
  /// mgrl::Error (removing the temporary) if `dir` meanwhile became something it may not
  /// replace, or on any I/O failure. Call at most once.
  void commit(std::string_view manifestText);

 private:
  bool replaceable(const std::filesystem::path& dir) const;

  std::filesystem::path dir_;
  std::string kind_;
  std::string manifestName_;
  Replaceable replaceable_;
  std::filesystem::path temporary_;
  bool committed_ = false;
};

/// What a killed writer left beside `dir`: `<dir>.tmp-PID-N` (a bundle being written; a
/// complete one when it holds its manifest) or `<dir>.old-PID-N` (a replaced bundle), of a
/// process that no longer exists.
struct StaleSibling {
  std::filesystem::path path;
  std::string tag;  ///< "tmp" or "old"
};
std::vector<StaleSibling> staleSiblings(const std::filesystem::path& dir);

/// Removes the stale siblings of `dir`; if `dir` is missing, first
/// puts back the newest complete one (a temporary holding `manifestName`, else an old
/// bundle). Those of live processes (this one included) are left alone. `log` hears what
/// was done.
void recoverBundleDirectory(const std::filesystem::path& dir, std::string_view manifestName,
                            const WarningSink& log = {});

/// A name beside `dir` that nothing has: `<dir>.<tag>-<pid>-<counter>`. With `create`, the
/// directory is made by the same call that proves the name free, so two writers never
/// share it. Throws mgrl::Error if it cannot be created or no free name is found.
std::filesystem::path freshSibling(const std::filesystem::path& dir, std::string_view tag, bool create);

/// Writes `bytes` to `path`, truncating it. Throws mgrl::Error naming the path on failure.
void writeWholeFile(const std::filesystem::path& path, std::string_view bytes);

/// True if `name` names a file directly inside a directory: not empty, not "." or "..",
/// without '/', '\\' or NUL.
bool isPlainFileName(std::string_view name);

/// `key` quoted for a message and cut to its first 16 characters: cache and run keys are
/// long hex digests, and 16 digits tell two apart.
std::string quoteKey(std::string_view key);

/// Python's repr of a shape tuple, as NumPy prints it: "(3,)", "(2, 3)", "()".
std::string formatShape(const std::vector<std::size_t>& shape);

/// The manifest entry of `file`, an encoded .npy of NumPy type `dtype` (npyDescr<T>()) and
/// dimensions `shape`: {"file", "dtype", "shape", "bytes", "hash"}, the hash being
/// hexDigest(hashBytes(file.bytes)) (mgrl/core/hash.hpp).
nlohmann::json bundleArrayEntry(const BundleFile& file, std::string_view dtype, const std::vector<std::size_t>& shape);

/// An array ready to go into a bundle: its .npy file and its manifest entry.
struct EncodedArray {
  BundleFile file;
  nlohmann::json entry;
};

/// npyEncode<T>(values, shape) as the file `fileName`, with its bundleArrayEntry().
/// Throws mgrl::Error if the shape does not match the number of values.
template <NpyElement T>
EncodedArray encodeBundleArray(std::string fileName, std::span<const T> values, const std::vector<std::size_t>& shape) {
  BundleFile file{std::move(fileName), npyEncode<T>(values, shape)};
  nlohmann::json entry = bundleArrayEntry(file, npyDescr<T>(), shape);
  return {std::move(file), std::move(entry)};
}

/// Reads members of a parsed manifest, checking each one's type, so that a hand-edited or
/// damaged manifest produces a message naming the member (`graph/manifest.json:
/// scalars.frames_total: expected an integer in [0, 4294967295], found '"20"'`) instead of
/// a json exception. `path` arguments are the dotted path of the parent ("" for the root);
/// every method throws mgrl::Error starting with source().
class ManifestReader {
 public:
  /// `source` is the manifest's path as shown in messages.
  explicit ManifestReader(std::string source) : source_(std::move(source)) {}

  /// Throws `<source>: <path>: expected <expected>, found <found, quoted>`.
  [[noreturn]] void fail(std::string_view path, std::string_view expected, const nlohmann::json& found) const;

  /// parent[key], which must exist.
  const nlohmann::json& member(const nlohmann::json& parent, std::string_view path, std::string_view key) const;
  /// parent[key], which must be an object with no keys besides `allowed` (any keys if
  /// `allowed` is empty).
  const nlohmann::json& object(const nlohmann::json& parent, std::string_view path, std::string_view key,
                               std::initializer_list<std::string_view> allowed) const;
  /// parent[key], which must be a string.
  std::string string(const nlohmann::json& parent, std::string_view path, std::string_view key) const;
  /// parent[key], which must be a number.
  double number(const nlohmann::json& parent, std::string_view path, std::string_view key) const;
  /// parent[key], which must be an integer in [0, max].
  std::uint64_t unsignedInteger(const nlohmann::json& parent, std::string_view path, std::string_view key,
                                std::uint64_t max) const;

  /// `path.key`, or `key` if path is empty.
  static std::string join(std::string_view path, std::string_view key);

  const std::string& source() const { return source_; }

 private:
  std::string source_;
};

/// The digest that seals a manifest: hexDigest(hashBytes()) of `manifest` without its
/// top-level "hash" member, dumped compactly (keys sorted, numbers in their shortest
/// round-trip form). It covers every value a reader parses, not the layout of the text, so
/// a manifest is written with `manifest["hash"] = manifestHash(manifest)` and checked by
/// checkManifestHash(). Throws nlohmann::json::type_error for strings that are not UTF-8.
std::string manifestHash(const nlohmann::json& manifest);

/// Requires `manifest["hash"]` to be a string equal to manifestHash(manifest), so that no
/// scalar of the manifest is trusted unchecked (array files have their own hashes). Throws
/// mgrl::Error `<source>: expected its members to hash to '<stored>' as its "hash" says,
/// found '<computed>' (the file was altered)`, or the reader's error if "hash" is missing
/// or not a string.
void checkManifestHash(const nlohmann::json& manifest, const ManifestReader& reader);

/// Reads and parses the manifest at `path`, which must hold a JSON object.
/// Throws mgrl::Error `<path>: expected JSON, found a syntax error (...)`,
/// `<path>: manifest: expected a JSON object, found ...`, or readFile()'s error.
nlohmann::json readManifestObject(const std::filesystem::path& path);

/// Loads the array whose entry is `parent[key]` (at `path` in the manifest) from the bundle
/// at `dir`. Checks, in this order: the entry is an object with exactly the keys of
/// bundleArrayEntry(); its file is `expectedFile` (or, if that is empty, any plain file
/// name, see isPlainFileName()); its dtype is npyDescr<T>(); the file exists and has the
/// entry's byte size (checked before reading it) and hash; it decodes strictly
/// (npyDecode()) to the entry's shape. If `shape` is given it receives the dimensions.
/// Throws mgrl::Error (or mgrl::ParseError from npyDecode()) whose message starts with the
/// manifest's or the array file's path, e.g. `policy/hit.q.npy: expected 4168 bytes as in
/// manifest.json, found 4000`.
/// An array of a bundle as mapBundleArray() found it: `data` views the mapped file in
/// place (or `copy`, where the file's data cannot be viewed), valid while this lives.
template <NpyElement T>
struct MappedBundleArray {
  std::unique_ptr<MappedFile> file;
  std::vector<T> copy;
  std::span<const T> data;
  std::vector<std::size_t> shape;
};

/// loadBundleArray() without copying the data out of the file: what the big arrays (Q
/// tables) use, so that loading one touches no fresh memory besides its destination.
template <NpyElement T>
MappedBundleArray<T> mapBundleArray(const std::filesystem::path& dir, const ManifestReader& manifest,
                                    const nlohmann::json& parent, std::string_view path, std::string_view key,
                                    std::string_view expectedFile);

template <NpyElement T>
std::vector<T> loadBundleArray(const std::filesystem::path& dir, const ManifestReader& manifest,
                               const nlohmann::json& parent, std::string_view path, std::string_view key,
                               std::string_view expectedFile, std::vector<std::size_t>* shape = nullptr);

}  // namespace mgrl
