#pragma once
/// \file
/// A skeleton: joints ordered parent before child, each with a rest offset from its parent
/// and the channels a file animates it with. Immutable once built.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "mgrl/core/rotation.hpp"

namespace mgrl {

/// One animated degree of freedom of a joint, as BVH lists them.
struct Channel {
  enum class Kind : unsigned char { Position, Rotation };
  Kind kind;
  Axis axis;

  bool operator==(const Channel&) const = default;
};

/// Name of a channel in BVH spelling, e.g. "Zrotation".
std::string channelName(const Channel& channel);
/// The channel channelName() spells `name` (exactly, e.g. "Zrotation"), or nullopt.
std::optional<Channel> channelFromName(std::string_view name);

struct Joint {
  std::string name;
  /// Index of the parent joint, -1 for the root (joint 0). Always smaller than the index.
  int parent = -1;
  /// Rest translation from the parent, in the parent's frame (metres once loaded).
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  /// Channels in file order; rotation channels compose left to right (see rotation.hpp).
  std::vector<Channel> channels;
  /// Point at the end of a leaf bone (BVH `End Site`), in this joint's frame.
  std::optional<Eigen::Vector3d> endSite;
};

/// Joints in parent-before-child order. A joint with position channels takes its local
/// translation from the motion each frame (the channels replace the offset; axes without
/// a channel keep the offset's value); other joints use their offset.
class Skeleton {
 public:
  /// Validates the ordering (parent < index, one root at 0) and unique non-empty names;
  /// throws mgrl::Error naming the offending joint.
  explicit Skeleton(std::vector<Joint> joints);

  std::size_t jointCount() const { return joints_.size(); }
  const Joint& joint(std::size_t index) const { return joints_[index]; }
  std::span<const Joint> joints() const { return joints_; }
  /// Index of the joint called `name` (exact match), or -1.
  int find(std::string_view name) const;

  /// Joints with position channels, in order; their slot in Motion's translation array
  /// is their index in this list.
  std::span<const int> translatedJoints() const { return translated_; }
  /// Slot of joint `index` among translatedJoints(), or -1 if it uses its offset.
  int translationSlot(std::size_t index) const { return slot_[index]; }
  /// Every joint's offset, contiguous (the local translations of a pose before the
  /// joints with position channels take theirs from the motion).
  std::span<const Eigen::Vector3d> offsets() const { return offsets_; }
  /// Number of channel values per frame.
  std::size_t channelCount() const { return channelCount_; }

  /// A copy with every length (offsets, end sites) multiplied by `factor`.
  Skeleton scaled(double factor) const;

  /// Names these contents: every constructed skeleton gets a new one, and copies keep it
  /// (a skeleton never changes once built), so equal ids mean equal joints and offsets,
  /// whatever the address. Pose::offsetsOf holds one.
  std::uint64_t id() const { return id_; }

  /// Comma-separated joint names, for error messages.
  std::string jointList() const;

 private:
  std::vector<Joint> joints_;
  std::vector<int> translated_;
  std::vector<int> slot_;
  std::vector<Eigen::Vector3d> offsets_;
  std::size_t channelCount_ = 0;
  std::uint64_t id_ = 0;
};

/// True if the joint has at least one position channel.
bool hasPositionChannel(const Joint& joint);

}  // namespace mgrl
