#pragma once
/// \file
/// Whole files in and out: read at once with a clear error, written atomically.
#include <filesystem>
#include <string>
#include <string_view>

namespace mgrl {

/// Reads a whole file; throws mgrl::Error saying why it could not.
std::string readFile(const std::filesystem::path& path);

/// Writes `text` to `path` through a temporary file in the same folder and a rename, so a
/// failure never leaves a partial file. Throws mgrl::Error on failure.
void writeFileAtomically(const std::filesystem::path& path, std::string_view text);

}  // namespace mgrl
