#pragma once
/// \file
/// Acclaim ASF (skeleton) and AMC (motion) reading, the CMU database's native format,
/// into the same Skeleton/Motion representation as BVH.
///
/// Each ASF bone becomes a joint at the bone's start, named after the bone, with the rest
/// pose world-aligned (identity rotations) like a BVH: its offset is the parent bone's
/// direction * length, a leaf bone gets an End Site, and its local rotation is
/// C * M * C^-1 (C from the bone's `axis`, M from the AMC degrees of freedom).

#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/motion.hpp"

namespace mgrl {

/// A parsed ASF: the converted skeleton plus what reading AMC frames needs.
struct AsfSkeleton {
  struct Bone {
    std::string name;
    /// Degrees of freedom in AMC value order: 0..2 = rx, ry, rz; 3..5 = tx, ty, tz (root only).
    std::vector<int> dofs;
    /// Local axis frame C (rotation) and its inverse.
    Eigen::Quaterniond axis = Eigen::Quaterniond::Identity();
    Eigen::Quaterniond axisInverse = Eigen::Quaterniond::Identity();
  };
  std::shared_ptr<const Skeleton> skeleton;
  /// bones[j] belongs to skeleton joint j; bones[0] is the root.
  std::vector<Bone> bones;
  /// Order of the root's rotation axes, as AMC composes them (R = R(o0) R(o1) R(o2) with
  /// o listed last-applied first; for `order ... RX RY RZ` this is Z, Y, X).
  std::vector<Axis> rootRotationOrder;
  /// The ASF `:units length` value: file lengths are inches times this (CMU: 0.45).
  double lengthPerInch = 1.0;
  /// True when angles are in degrees (`:units angle deg`, the default).
  bool degrees = true;
};

/// Parses ASF text. Throws ParseError on malformed input, including unknown keywords,
/// duplicate bone names, bones the hierarchy does not reach and hierarchy cycles.
AsfSkeleton parseAsf(std::string_view text, std::string_view source);
AsfSkeleton readAsf(std::istream& in, std::string_view source);

/// Parses AMC text for `asf`. Frames are `frameTime` seconds apart (AMC does not store it;
/// CMU captures at 120 fps). Lengths stay in ASF file units. Throws ParseError on
/// malformed input, including bones the ASF does not have, wrong value counts and frames
/// missing a bone.
Motion parseAmc(std::string_view text, std::string_view source, const AsfSkeleton& asf, double frameTime = 1.0 / 120.0);
Motion readAmc(std::istream& in, std::string_view source, const AsfSkeleton& asf, double frameTime = 1.0 / 120.0);

}  // namespace mgrl
