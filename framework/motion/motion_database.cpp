#include "mgrl/motion/motion_database.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "mgrl/motion/motion_io.hpp"
#include "mgrl/motion/root_motion.hpp"

namespace mgrl {

namespace {

// A joint's local translation at rest: its offset, or, when the file animates it (game
// exports give every joint position channels), its first frame's channel values, unless
// those move by more than 1 cm over the clip (a joint that carries travel, like hips that
// bake the take's start position in): then nullopt, there is no fixed bone to compare.
std::optional<Eigen::Vector3d> fixedBone(const Motion& motion, std::size_t joint) {
  if (motion.skeleton().translationSlot(joint) < 0) return motion.skeleton().joint(joint).offset;
  const Eigen::Vector3d first = motion.localTranslation(0, joint);
  for (std::size_t f = 1; f < motion.frameCount(); ++f)
    if ((motion.localTranslation(f, joint) - first).norm() > 0.01) return std::nullopt;
  return first;
}

// Files of one graph must share joints and hierarchy; bone lengths may differ a little
// (capture sessions recalibrate) but a different body would make transitions meaningless.
// Bones are compared where they are fixed (fixedBone()): one actor's takes that each bake
// their start position into the hips still load together.
void requireSameSkeleton(const Motion& ma, std::string_view nameA, const Motion& mb, std::string_view nameB) {
  const Skeleton& a = ma.skeleton();
  const Skeleton& b = mb.skeleton();
  if (a.jointCount() != b.jointCount())
    throw Error(fmt::format("{} and {} have different skeletons: expected {} joints, found {}", nameA, nameB,
                            a.jointCount(), b.jointCount()));
  for (std::size_t j = 0; j < a.jointCount(); ++j) {
    const Joint& ja = a.joint(j);
    const Joint& jb = b.joint(j);
    if (ja.name != jb.name || ja.parent != jb.parent)
      throw Error(
          fmt::format("{} and {} have different skeletons: joint {} is '{}' (parent {}) in the first, "
                      "'{}' (parent {}) in the second",
                      nameA, nameB, j, ja.name, ja.parent, jb.name, jb.parent));
    if (j == 0) continue;  // the root's offset is replaced by its position channels
    const std::optional<Eigen::Vector3d> boneA = fixedBone(ma, j), boneB = fixedBone(mb, j);
    if (!boneA || !boneB) continue;
    const double la = boneA->norm(), lb = boneB->norm();
    if (std::abs(la - lb) > 0.01 + 0.05 * std::max(la, lb))
      throw Error(
          fmt::format("{} and {} have different skeletons: bone '{}' is {:.3f} m in the first, {:.3f} m in "
                      "the second (more than 5 % apart)",
                      nameA, nameB, ja.name, la, lb));
  }
}

}  // namespace

std::size_t MotionDatabase::clipOf(std::uint32_t frame) const {
  const auto it = std::upper_bound(offsets.begin(), offsets.end(), frame);
  return static_cast<std::size_t>(it - offsets.begin()) - 1;
}

std::size_t MotionDatabase::hitCount() const {
  std::size_t n = 0;
  for (const Clip& c : clips) n += c.annotation.hits.size();
  return n;
}

std::size_t MotionDatabase::kickCount() const {
  std::size_t n = 0;
  for (const Clip& c : clips) n += c.annotation.kicks.size();
  return n;
}

MotionDatabase makeMotionDatabase(std::vector<std::pair<std::string, Motion>> motions, const RoleOverrides& roles,
                                  const AnnotationParams& annotation, const WarningSink& warn) {
  if (motions.empty()) throw Error("motion: expected at least one motion file, found none");
  annotation.validate();
  MotionDatabase db;
  db.frameTime = motions.front().second.frameTime();
  db.roles = findRoles(motions.front().second.skeleton(), roles, motions.front().first, warn);
  // Joint 0 carries the travel from here on (root_motion.hpp); a file whose root stays at
  // the origin above the hips gets its motion from the hips.
  for (auto& [name, motion] : motions) motion = moveRootToPelvis(motion, db.roles.pelvis, name, db.rootMotion);
  db.skeleton = motions.front().second.sharedSkeleton();
  if (db.roles.pelvis != 0) db.roles = findRoles(*db.skeleton, roles, motions.front().first);
  db.offsets.push_back(0);
  for (auto& [name, motion] : motions) {
    // The first clip has moved into db.clips by the second one's turn.
    if (!db.clips.empty()) requireSameSkeleton(db.clips.front().motion, db.clips.front().name, motion, name);
    if (std::abs(motion.frameTime() - db.frameTime) > 1e-9)
      throw Error(fmt::format("{}: expected {} fps like {}, found {} fps", name, 1.0 / db.frameTime,
                              motions.front().first, motion.fps()));
    const std::uint64_t total = std::uint64_t{db.offsets.back()} + motion.frameCount();
    if (total > std::uint64_t{1} << 30)
      throw Error(fmt::format("motion: expected at most 2^30 frames in one graph, found {}", total));
    db.clips.push_back(Clip{name, {}, std::move(motion), {}});
    db.offsets.push_back(static_cast<std::uint32_t>(total));
  }
  // `punch_min_speed_mps: auto` chooses one threshold over every clip, so one actor's
  // takes are judged alike.
  AnnotationParams params = annotation;
  if (params.punchMinSpeedAuto) {
    std::vector<const Motion*> all;
    for (const Clip& clip : db.clips) all.push_back(&clip.motion);
    db.autoPunchSpeed = autoPunchMinSpeed(all, db.roles, params);
    params.punchMinSpeed_mps = db.autoPunchSpeed->speed_mps;
    params.punchMinSpeedAuto = false;
  }
  for (Clip& clip : db.clips) {
    clip.annotation = annotate(clip.motion, db.roles, params);
    if (const std::string unusual = unusualHeightWarning(clip.annotation, clip.name); !unusual.empty() && warn)
      warn(unusual);
  }
  return db;
}

MotionDatabase loadMotionDatabase(const MotionSpec& spec, const WarningSink& warn) {
  if (spec.files.empty()) throw Error("motion.files: expected at least one motion file, found none");
  std::vector<std::pair<std::string, Motion>> motions;
  motions.reserve(spec.files.size());
  for (const auto& file : spec.files) {
    LoadOptions options;
    options.units = spec.units;
    options.fps = spec.fps;
    options.asf = spec.asf;
    options.warn = warn;
    LoadedMotion loaded = loadMotion(file, options);
    motions.emplace_back(file.filename().string(), std::move(loaded.motion));
  }
  return makeMotionDatabase(std::move(motions), spec, warn);
}

MotionDatabase makeMotionDatabase(std::vector<std::pair<std::string, Motion>> motions, const MotionSpec& spec,
                                  const WarningSink& warn) {
  if (motions.size() != spec.files.size())
    throw Error(
        fmt::format("motion.files: expected one motion per file ({}), found {}", spec.files.size(), motions.size()));
  MotionDatabase db = makeMotionDatabase(std::move(motions), spec.roles, spec.annotation, warn);
  for (std::size_t c = 0; c < db.clips.size(); ++c) db.clips[c].path = spec.files[c];
  return db;
}

}  // namespace mgrl
