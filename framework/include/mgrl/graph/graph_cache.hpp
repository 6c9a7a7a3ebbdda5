#pragma once
/// \file
/// The graph cache bundle (DESIGN.md sec. 6): a directory holding `manifest.json` and one
/// NumPy .npy file per array of a StateActionModel, so building the motion graph is done
/// once per scenario and data, and a student can open the arrays with `numpy.load`.
///
/// manifest.json:
///
///     {"format": "mgrl.graph", "version": 2,
///      "provenance": {"key": "<cache key>", ...whatever the caller records},
///      "scalars": {"frame_time": s, "frames_total": n, "centroid": [x, y, z],
///                  "max_hit_speed_mps": v},
///      "arrays": {"action_frames": {"file": "action_frames.npy", "dtype": "<u4",
///                                   "shape": [F], "bytes": size, "hash": "<xxh64 hex>"},
///                 ...},
///      "hash": "<xxh64 hex of all the other members>"}
///
/// Arrays, named after the fields in snake_case: clip_offset, component_frames,
/// transitions (T, 2), transition_distance, state_frame, action_from, action_to,
/// action_frame_begin, action_displacement (A, 3), state_action_begin, action_frames,
/// frame_root (F, 3), frame_centroid (F, 3), frame_enters_transition, action_hit_begin, and
/// the hits split by type: hits_index (H, 3) uint32 (action, offset, hand) and hits_value
/// (H, 4) float32 (x, y, z, weight). An array's hash is hexDigest(hashBytes(file bytes))
/// (mgrl/core/hash.hpp: XXH64); the manifest's own "hash" is manifestHash()
/// (mgrl/core/bundle.hpp), so the scalars and provenance are checked as the arrays are.
/// Version 2 added that hash: a version 1 bundle trusted its scalars unchecked. Version 3
/// added the effective kicks: kicks_index (K, 3) (action, offset, foot), kicks_value (K, 4),
/// action_kick_begin and the scalar max_kick_speed_mps.
///
/// Version 5 added the skeleton's joints for body points (StateActionModel::jointNames):
/// the scalar joint_names (J strings), role_joint (R,) int32, source_joint (F * J, 3)
/// float32 and source_joint_speed (F * J,) float32.
///
/// Version 4 may keep the capture the graph was built from, resampled and in metres, so
/// that posing avatars from a cached graph (simulate, the viewer, `mgrl graph`) does not
/// parse it again, so that commands start quickly: a top-level "motion" member
///
///     "motion": {"clips": [{"name": "13_17_boxing.bvh", "frames": F, "frame_time": s,
///                           "joints": [{"name": "Hips", "parent": -1, "offset": [x, y, z],
///                                       "channels": ["Xposition", ..., "Zrotation"],
///                                       "end_site": [x, y, z]}, ...]}, ...]}
///
/// ("end_site" only where the joint has one) and the arrays motion_rotations (R, 4)
/// float64, every clip's local joint rotations frame after frame as quaternions (x, y, z,
/// w), R the sum of frames x joints over the clips, and motion_translations (S, 3)
/// float64, the local translations of the joints with position channels, S the sum of
/// frames x such joints. The annotations (contacts, effective hits) are not kept: they are
/// recomputed from these (makeMotionDatabase(), a few milliseconds), so they always follow
/// the annotation code and parameters of the reader.

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/motion/motion_database.hpp"

namespace mgrl {

/// The manifest's "format" and "version"; a bundle with others is Stale.
inline constexpr std::string_view kGraphFormatName = "mgrl.graph";
inline constexpr int kGraphFormatVersion = 5;

/// Limits on a bundle's "motion" member, checked before anything is allocated for it.
inline constexpr std::size_t kMaxBundledClips = 100'000;
inline constexpr std::size_t kMaxBundledJoints = 1'000;

/// Writes `m` as a bundle at `dir` (see the file comment), replacing a bundle already there.
/// With `clips` (the capture `m` was built from), their motions go in too ("motion").
/// `provenance` must be a JSON object with a string "key", the cache key loadGraphBundle()
/// compares; the rest is recorded as is. The files go to a sibling temporary directory
/// that is then renamed onto `dir` (an old bundle is first renamed aside, then removed),
/// so a crash leaves either a whole bundle at `dir` or none; a power loss may still leave
/// files with lost contents, which loadGraphBundle() reports as Damaged by their hashes.
/// Writes the same bytes for the same model and provenance. Creates `dir`'s parent if
/// needed. Not safe against another process saving to the same `dir` at the same time.
/// Throws mgrl::Error (leaving no temporary directory) if checkModel() fails, if
/// provenance has no string "key", if `dir` is something other than a bundle or an empty
/// directory (it is never deleted then), or on any I/O failure.
void saveGraphBundle(const std::filesystem::path& dir, const StateActionModel& m, const nlohmann::json& provenance,
                     std::span<const Clip> clips = {});

/// What loadGraphBundle() found.
struct GraphBundleLoad {
  enum Status {
    Missing,  ///< no directory at the path
    Stale,    ///< a readable manifest for another cache key, format or version
    Damaged,  ///< anything else wrong: unreadable, incomplete, altered or invalid
    Ok,       ///< `model` holds the bundle, checked by checkModel()
  };
  Status status = Missing;
  /// Why the bundle is not Ok, starting with the path of the file concerned, e.g.
  /// `graph/action_to.npy: expected 48 bytes as in manifest.json, found 44`; empty if Ok.
  std::string reason;
  StateActionModel model;  ///< filled only if Ok
  /// The bundle's clips (name and motion), filled only if Ok, asked for, and kept.
  std::vector<std::pair<std::string, Motion>> motions;
  nlohmann::json manifest;  ///< the parsed manifest if Stale or Ok, else null
};

/// Loads the bundle at `dir` if it is whole, unaltered and made for `expectedKey`
/// (provenance.key). Checks the format and version, the manifest's hash (so every scalar
/// and provenance value is as saved), every array's file name, dtype, shape,
/// byte size and hash against the manifest, decodes the arrays strictly (mgrl/core/npy.hpp) and
/// runs checkModel() on the result. With `withMotion`, also reads the clips the bundle keeps
/// (none for a bundle saved without them), checking their arrays the same way, each
/// skeleton (Skeleton's own checks) and that the frames add up to the model's. Never throws
/// for a bad bundle: the status and reason say what is wrong, and the caller rebuilds.
GraphBundleLoad loadGraphBundle(const std::filesystem::path& dir, std::string_view expectedKey,
                                bool withMotion = false);

}  // namespace mgrl
