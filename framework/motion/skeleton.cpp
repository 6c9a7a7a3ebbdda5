#include "mgrl/motion/skeleton.hpp"

#include <atomic>
#include <unordered_map>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

std::string channelName(const Channel& channel) {
  return fmt::format("{}{}", axisLetter(channel.axis),
                     channel.kind == Channel::Kind::Position ? "position" : "rotation");
}

std::optional<Channel> channelFromName(std::string_view name) {
  if (name.size() != 9 || name[0] < 'X' || name[0] > 'Z') return std::nullopt;
  const Axis axis = static_cast<Axis>(name[0] - 'X');
  if (name.substr(1) == "position") return Channel{Channel::Kind::Position, axis};
  if (name.substr(1) == "rotation") return Channel{Channel::Kind::Rotation, axis};
  return std::nullopt;
}

bool hasPositionChannel(const Joint& joint) {
  for (const Channel& c : joint.channels)
    if (c.kind == Channel::Kind::Position) return true;
  return false;
}

Skeleton::Skeleton(std::vector<Joint> joints) : joints_(std::move(joints)) {
  if (joints_.empty()) throw Error("skeleton: expected at least one joint, found none");
  std::unordered_map<std::string_view, std::size_t> seen;
  slot_.assign(joints_.size(), -1);
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const Joint& joint = joints_[i];
    if (joint.name.empty()) throw Error(fmt::format("skeleton: joint {}: expected a name, found an empty one", i));
    if (!seen.emplace(joint.name, i).second)
      throw Error(fmt::format("skeleton: expected unique joint names, found '{}' twice", joint.name));
    if (i == 0 ? joint.parent != -1 : (joint.parent < 0 || joint.parent >= static_cast<int>(i)))
      throw Error(fmt::format("skeleton: joint '{}' (index {}): expected a parent index {}, found {}", joint.name, i,
                              i == 0 ? "of -1 (the root)" : fmt::format("in [0, {})", i), joint.parent));
    if (hasPositionChannel(joint)) {
      slot_[i] = static_cast<int>(translated_.size());
      translated_.push_back(static_cast<int>(i));
    }
    channelCount_ += joint.channels.size();
    offsets_.push_back(joint.offset);
  }
  static std::atomic<std::uint64_t> built{0};
  id_ = built.fetch_add(1, std::memory_order_relaxed) + 1;  // 0 names no skeleton
}

int Skeleton::find(std::string_view name) const {
  for (std::size_t i = 0; i < joints_.size(); ++i)
    if (joints_[i].name == name) return static_cast<int>(i);
  return -1;
}

Skeleton Skeleton::scaled(double factor) const {
  std::vector<Joint> joints = joints_;
  for (Joint& joint : joints) {
    joint.offset *= factor;
    if (joint.endSite) *joint.endSite *= factor;
  }
  return Skeleton(std::move(joints));
}

std::string Skeleton::jointList() const {
  std::string names;
  for (const Joint& joint : joints_) {
    if (!names.empty()) names += ", ";
    names += joint.name;
  }
  return names;
}

}  // namespace mgrl
