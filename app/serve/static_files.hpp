#pragma once
/// \file
/// Which file under the web folder an HTTP request names, or why none
/// (docs/viewer-protocol.md, HTTP): percent-decoding once, no `.` or `..` segments, no
/// backslash or NUL, nothing that resolves outside the folder.
#include <filesystem>
#include <string>
#include <string_view>

namespace mgrl::serve {

struct StaticLookup {
  int status = 200;            ///< 200, 400 or 404
  std::filesystem::path file;  ///< the file, when 200
  std::string reason;          ///< why not, for the response body
};

/// `root` must be canonical (std::filesystem::canonical).
StaticLookup lookupStatic(const std::filesystem::path& root, std::string_view target);

/// The MIME type for a file name's extension.
std::string_view mimeType(const std::filesystem::path& file);

}  // namespace mgrl::serve
