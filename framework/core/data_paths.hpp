#pragma once
/// \file
/// Where the motion capture lives: `--data DIR`, else the MGRL_DATA environment variable,
/// else `../shared/mocap` next to the repository root (DESIGN.md sec. 6).

#include <filesystem>

namespace mgrl {

/// The data folder. `explicitDir` (from --data) wins when not empty. Does not check that
/// the folder exists.
std::filesystem::path dataDirectory(const std::filesystem::path& explicitDir = {});

}  // namespace mgrl
