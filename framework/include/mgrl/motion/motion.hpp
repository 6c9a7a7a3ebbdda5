#pragma once
/// \file
/// A motion clip: per frame, a local rotation for every joint and a local translation for
/// every joint with position channels. Immutable once built; lengths in metres after
/// loading (see motion_io.hpp).

#include <memory>
#include <span>
#include <vector>

#include <Eigen/Geometry>

#include "mgrl/motion/skeleton.hpp"

namespace mgrl {

class Motion {
 public:
  /// `rotations` holds frameCount * jointCount quaternions (frame-major), `translations`
  /// frameCount * translatedJoints().size() vectors. Throws mgrl::Error if the sizes do not
  /// agree, there is no frame, or frameTime is not positive.
  Motion(std::shared_ptr<const Skeleton> skeleton, double frameTime, std::vector<Eigen::Quaterniond> rotations,
         std::vector<Eigen::Vector3d> translations);

  const Skeleton& skeleton() const { return *skeleton_; }
  const std::shared_ptr<const Skeleton>& sharedSkeleton() const { return skeleton_; }

  std::size_t frameCount() const { return frameCount_; }
  /// Seconds between frames.
  double frameTime() const { return frameTime_; }
  double fps() const { return 1.0 / frameTime_; }
  /// frameCount * frameTime, in seconds (the length of the clip as capture tools report it).
  double duration() const { return static_cast<double>(frameCount_) * frameTime_; }

  const Eigen::Quaterniond& rotation(std::size_t frame, std::size_t joint) const {
    return rotations_[frame * skeleton_->jointCount() + joint];
  }
  std::span<const Eigen::Quaterniond> rotations(std::size_t frame) const {
    return {rotations_.data() + frame * skeleton_->jointCount(), skeleton_->jointCount()};
  }
  /// Local translation of `joint` at `frame`: the animated value or the rest offset.
  Eigen::Vector3d localTranslation(std::size_t frame, std::size_t joint) const {
    const int slot = skeleton_->translationSlot(joint);
    return slot < 0 ? skeleton_->joint(joint).offset
                    : translations_[frame * skeleton_->translatedJoints().size() + slot];
  }
  std::span<const Eigen::Vector3d> translations(std::size_t frame) const {
    const std::size_t n = skeleton_->translatedJoints().size();
    return {translations_.data() + frame * n, n};
  }

  /// A copy with every length multiplied by `factor` (unit conversion).
  Motion scaled(double factor) const;
  /// Frames [first, first + count) as a new clip sharing the skeleton.
  Motion slice(std::size_t first, std::size_t count) const;

 private:
  std::shared_ptr<const Skeleton> skeleton_;
  double frameTime_;
  std::size_t frameCount_;
  std::vector<Eigen::Quaterniond> rotations_;
  std::vector<Eigen::Vector3d> translations_;
};

/// Limits of resample(): frames made, and bytes of rotations and translations.
inline constexpr std::size_t kMaxResampledFrames = 10'000'000;
inline constexpr double kMaxResampledBytes = 4e9;

/// Resamples to `fps` frames per second: sample k at time k / fps, rotations slerped along
/// the shorter arc, translations interpolated linearly. Keeps the duration to within one
/// output frame. Throws mgrl::Error unless 0 < fps <= 10000, and, before allocating,
/// when the result would exceed kMaxResampledFrames frames or kMaxResampledBytes.
Motion resample(const Motion& motion, double fps);

}  // namespace mgrl
