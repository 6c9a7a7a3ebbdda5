#pragma once
/// \file
/// The capture a motion graph is built from: several clips on one skeleton, resampled to
/// one frame rate, annotated (contacts, effective hits), numbered globally in file order.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/motion.hpp"
#include "mgrl/motion/roles.hpp"
#include "mgrl/motion/root_motion.hpp"
#include "mgrl/motion/units.hpp"

namespace mgrl {

/// What to load: a scenario's `motion:` section with its paths resolved.
struct MotionSpec {
  std::vector<std::filesystem::path> files;  ///< .bvh or .amc, in graph order
  double fps = 30;                           ///< every clip is resampled to this rate
  LengthUnit units = LengthUnit::Auto;
  std::filesystem::path asf;  ///< skeleton for .amc files; empty: by CMU naming
  RoleOverrides roles;
  AnnotationParams annotation;
};

struct Clip {
  std::string name;  ///< file name without folder
  std::filesystem::path path;
  Motion motion;  ///< metres, resampled
  Annotation annotation;
};

/// Clips sharing one skeleton (same joints, hierarchy and, within 5 %, bone lengths).
struct MotionDatabase {
  std::shared_ptr<const Skeleton> skeleton;  ///< the first clip's
  SkeletonRoles roles;
  /// Which joint carries the root motion, and why (root_motion.hpp): the last clip's.
  RootMotionReport rootMotion;
  /// What `punch_min_speed_mps: auto` chose over every clip; empty when the threshold was given.
  std::optional<AutoPunchSpeed> autoPunchSpeed;
  std::vector<Clip> clips;
  /// Global index of each clip's first frame, plus the total at the end.
  std::vector<std::uint32_t> offsets;
  double frameTime = 0;

  std::uint32_t frameCount() const { return offsets.back(); }
  /// Clip index of global frame `frame` (< frameCount()).
  std::size_t clipOf(std::uint32_t frame) const;
  const Clip& clipAt(std::uint32_t frame) const { return clips[clipOf(frame)]; }
  /// Frame index within its clip.
  std::size_t localFrame(std::uint32_t frame) const { return frame - offsets[clipOf(frame)]; }
  /// Effective hitting points and kick frames in every clip's annotation.
  std::size_t hitCount() const;
  std::size_t kickCount() const;
};

/// Loads, resamples and annotates every file of `spec`. Throws mgrl::Error when there is
/// no file, a file cannot be read, or two files have different skeletons (naming the first
/// difference), and ParseError for malformed files. Warnings go to `warn`.
MotionDatabase loadMotionDatabase(const MotionSpec& spec, const WarningSink& warn = {});

/// The same from motions already in memory (metres, one frame rate), for tests and tools.
/// Warnings (a fist standing in for a missing one, an unusual standing height) go to `warn`.
MotionDatabase makeMotionDatabase(std::vector<std::pair<std::string, Motion>> motions, const RoleOverrides& roles = {},
                                  const AnnotationParams& annotation = {}, const WarningSink& warn = {});

/// The same for `spec`'s files, parsed already (one motion per file, in its order): the
/// roles and annotation come from `spec`, and each clip's path is its file's.
MotionDatabase makeMotionDatabase(std::vector<std::pair<std::string, Motion>> motions, const MotionSpec& spec,
                                  const WarningSink& warn = {});

}  // namespace mgrl
