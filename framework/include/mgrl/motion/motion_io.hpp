#pragma once
/// \file
/// Loading motion files by path, with unit conversion to metres and optional resampling,
/// and writing BVH files atomically.

#include <filesystem>
#include <string>

#include "mgrl/core/error.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/motion.hpp"
#include "mgrl/motion/units.hpp"

namespace mgrl {

struct LoadOptions {
  /// Units of the file's lengths. Auto: an ASF's own `:units length`; for BVH, the unit
  /// that makes the rest-pose standing height most plausible (roles.hpp).
  LengthUnit units = LengthUnit::Auto;
  /// Resample to this frame rate; 0 keeps the file's.
  double fps = 0;
  /// Skeleton for an AMC file; empty: `<subject>.asf` beside it (13_17.amc -> 13.asf).
  std::filesystem::path asf;
  /// Frame rate of AMC files, which do not store one (CMU: 120).
  double amcFps = 120;
  WarningSink warn;
};

struct LoadedMotion {
  Motion motion;  ///< in metres, resampled if asked
  /// The unit the file was read in; Auto only for an ASF whose `:units length` is none of
  /// the named units (its own scale was applied).
  LengthUnit units;
  double fileFps;  ///< frame rate before resampling
};

/// Loads a .bvh or .amc file (by extension, case-insensitive). Throws ParseError for a
/// malformed file and mgrl::Error for anything else (missing file, unknown extension,
/// units that cannot be detected).
LoadedMotion loadMotion(const std::filesystem::path& path, const LoadOptions& options = {});

/// The ASF an AMC file goes with by CMU naming: the part of its name before the first
/// '_' plus ".asf", in the same folder.
std::filesystem::path defaultAsfFor(const std::filesystem::path& amc);

/// writeBvh() into `path`, atomically.
void writeBvhFile(const std::filesystem::path& path, const Motion& motion, const BvhWriteOptions& options = {});

}  // namespace mgrl
