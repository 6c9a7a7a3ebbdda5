#pragma once
// Shared by the libFuzzer harnesses (tests/fuzz/README.md): what counts as a
// finding, inputs that hold several files, and a scratch folder per process.
//
// A reader may refuse any input with mgrl::Error (one clear message); anything else is a
// finding: another exception (reported here, then abort() so libFuzzer saves the input),
// a sanitizer report, a crash, a timeout or an allocation above -malloc_limit_mb.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "mgrl/core/error.hpp"

namespace mgrl::fuzz {

/// Runs `read`; mgrl::Error is the reader's refusal, any other exception aborts.
template <class Read>
void guarded(const char* reader, Read&& read) {
  try {
    read();
  } catch (const mgrl::Error&) {
    // A clear refusal: what a reader is for.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FINDING in %s: %s escaped: %s\n", reader, typeid(e).name(), e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "FINDING in %s: a non-standard exception escaped\n", reader);
    std::abort();
  }
}

inline std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// A folder of its own for this process, made on first use, emptied by clear().
class Scratch {
 public:
  Scratch() {
    const char* base = std::getenv("TMPDIR");
    path_ = std::filesystem::path(base && *base ? base : "/tmp") / ("mgrl-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(path_);
  }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  const std::filesystem::path& path() const { return path_; }
  /// A fresh empty folder `name` inside.
  std::filesystem::path fresh(const std::string& name) const {
    std::error_code ignored;
    std::filesystem::remove_all(path_ / name, ignored);
    std::filesystem::create_directories(path_ / name);
    return path_ / name;
  }

 private:
  std::filesystem::path path_;
};

/// An input holding several files of a bundle: the first file is the manifest, each next
/// one starts after a line `\n@@file NAME\n` (NAME a plain file name). A mutated
/// separator only merges two files, which the readers must survive too.
struct File {
  std::string name;
  std::string bytes;
};
inline std::vector<File> splitFiles(std::string_view input, const std::string& firstName) {
  constexpr std::string_view marker = "\n@@file ";
  std::vector<File> files;
  std::string name = firstName;
  for (;;) {
    const std::size_t at = input.find(marker);
    if (at == std::string_view::npos) {
      files.push_back({name, std::string(input)});
      return files;
    }
    files.push_back({name, std::string(input.substr(0, at))});
    input.remove_prefix(at + marker.size());
    const std::size_t end = input.find('\n');
    name = std::string(input.substr(0, end));
    input.remove_prefix(end == std::string_view::npos ? input.size() : end + 1);
  }
}
/// The inverse of splitFiles(): the seed corpora are made with it.
inline std::string joinFiles(const std::vector<File>& files) {
  std::string out;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (i > 0) out += "\n@@file " + files[i].name + "\n";
    out += files[i].bytes;
  }
  return out;
}

/// True for a name a harness may write inside its folder (no path, not too long).
inline bool plainName(const std::string& name) {
  return !name.empty() && name.size() < 100 && name != "." && name != ".." &&
         name.find_first_of(std::string_view("/\0", 2)) == std::string::npos;
}

}  // namespace mgrl::fuzz

#include <fstream>

#include <nlohmann/json.hpp>

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/hash.hpp"

namespace mgrl::fuzz {

/// Writes `files` into `dir` (plain names only; a repeated name keeps the last).
inline void writeFiles(const std::filesystem::path& dir, const std::vector<File>& files) {
  for (const File& file : files) {
    if (!plainName(file.name)) continue;
    std::ofstream(dir / file.name, std::ios::binary).write(file.bytes.data(), static_cast<std::streamsize>(file.bytes.size()));
  }
}

/// The bundle readers check hashes first, so a mutated file stops there. To reach the
/// checks behind them, a harness also loads the input "resealed": every manifest entry
/// naming one of the input's files gets that file's true size and hash, and the manifest
/// `hashKey` (manifestHash()) is recomputed. A bundle edited by a script that fixes its
/// hashes looks like this, and must be refused as clearly. Returns false if the manifest is
/// not a JSON object (nothing to reseal).
inline bool reseal(std::vector<File>& files, const char* hashKey = "hash") {
  nlohmann::json manifest = nlohmann::json::parse(files.front().bytes, nullptr, false);
  if (!manifest.is_object()) return false;
  auto bytesOf = [&](const std::string& name) -> const std::string* {
    for (auto it = files.rbegin(); it != files.rend(); ++it)
      if (it->name == name) return &it->bytes;
    return nullptr;
  };
  auto walk = [&](auto&& self, nlohmann::json& node, int depth) -> void {
    if (depth > 64) return;
    if (node.is_object()) {
      auto file = node.find("file");
      if (file != node.end() && file->is_string())
        if (const std::string* bytes = bytesOf(file->get<std::string>())) {
          if (node.contains("bytes")) node["bytes"] = bytes->size();
          if (node.contains("hash")) node["hash"] = hexDigest(hashBytes(*bytes));
        }
      for (auto& [key, value] : node.items()) self(self, value, depth + 1);
    } else if (node.is_array()) {
      for (auto& value : node) self(self, value, depth + 1);
    }
  };
  walk(walk, manifest, 0);
  try {
    if (manifest.contains(hashKey)) manifest[hashKey] = manifestHash(manifest);
    files.front().bytes = manifest.dump(1);
  } catch (const nlohmann::json::exception&) {
    return false;  // strings that are not UTF-8: the raw load covers them
  }
  return true;
}

}  // namespace mgrl::fuzz
