#include "mgrl/motion/motion.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

Motion::Motion(std::shared_ptr<const Skeleton> skeleton, double frameTime,
               std::vector<Eigen::Quaterniond> rotations, std::vector<Eigen::Vector3d> translations)
    : skeleton_(std::move(skeleton)),
      frameTime_(frameTime),
      frameCount_(0),
      rotations_(std::move(rotations)),
      translations_(std::move(translations)) {
  if (!skeleton_) throw Error("motion: expected a skeleton, found none");
  if (!(frameTime_ > 0) || !std::isfinite(frameTime_))
    throw Error(fmt::format("motion: expected a positive frame time, found {}", frameTime_));
  const std::size_t joints = skeleton_->jointCount();
  frameCount_ = rotations_.size() / joints;
  if (frameCount_ == 0 || rotations_.size() != frameCount_ * joints ||
      translations_.size() != frameCount_ * skeleton_->translatedJoints().size())
    throw Error(fmt::format("motion: expected {} rotations and {} translations per frame, found {} and {}",
                            joints, skeleton_->translatedJoints().size(), rotations_.size(),
                            translations_.size()));
}

Motion Motion::scaled(double factor) const {
  std::vector<Eigen::Vector3d> translations = translations_;
  for (Eigen::Vector3d& t : translations) t *= factor;
  return Motion(std::make_shared<const Skeleton>(skeleton_->scaled(factor)), frameTime_, rotations_,
                std::move(translations));
}

Motion Motion::slice(std::size_t first, std::size_t count) const {
  if (count == 0 || first + count > frameCount_)
    throw Error(fmt::format("motion: expected a frame range inside [0, {}), found [{}, {})", frameCount_,
                            first, first + count));
  const std::size_t joints = skeleton_->jointCount();
  const std::size_t translated = skeleton_->translatedJoints().size();
  return Motion(skeleton_, frameTime_,
                {rotations_.begin() + static_cast<std::ptrdiff_t>(first * joints),
                 rotations_.begin() + static_cast<std::ptrdiff_t>((first + count) * joints)},
                {translations_.begin() + static_cast<std::ptrdiff_t>(first * translated),
                 translations_.begin() + static_cast<std::ptrdiff_t>((first + count) * translated)});
}

Motion resample(const Motion& motion, double fps) {
  if (!(fps > 0) || fps > 10000 || !std::isfinite(fps))
    throw Error(fmt::format("resample: expected a frame rate in (0, 10000], found {}", fps));
  const Skeleton& skeleton = motion.skeleton();
  const std::size_t joints = skeleton.jointCount();
  const std::size_t translated = skeleton.translatedJoints().size();
  // The size is checked before anything is reserved (a long frame time times a
  // high rate asked for gigabytes).
  const double frames = std::max(1.0, std::round(motion.duration() * fps));
  const double bytes = frames * (static_cast<double>(joints) * sizeof(Eigen::Quaterniond) +
                                 static_cast<double>(translated) * sizeof(Eigen::Vector3d));
  if (frames > static_cast<double>(kMaxResampledFrames) || bytes > kMaxResampledBytes)
    throw Error(fmt::format("resample: {:.1f} s of motion at {} fps is {:.0f} frames ({:.2f} GB); expected at most {} "
                            "frames and {:.0f} GB",
                            motion.duration(), fps, frames, bytes / 1e9, kMaxResampledFrames, kMaxResampledBytes / 1e9));
  const auto count = static_cast<std::size_t>(frames);
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  rotations.reserve(count * joints);
  translations.reserve(count * translated);
  const std::size_t last = motion.frameCount() - 1;
  for (std::size_t k = 0; k < count; ++k) {
    // Source position of output sample k; exact source frames stay bit-identical.
    const double source = std::min(static_cast<double>(k) / fps / motion.frameTime(), static_cast<double>(last));
    std::size_t i0 = static_cast<std::size_t>(std::floor(source));
    double u = source - static_cast<double>(i0);
    if (u < 1e-9) u = 0;
    if (u > 1 - 1e-9) {
      u = 0;
      i0 = std::min(i0 + 1, last);
    }
    const std::size_t i1 = std::min(i0 + 1, last);
    for (std::size_t j = 0; j < joints; ++j) {
      const Eigen::Quaterniond& a = motion.rotation(i0, j);
      rotations.push_back(u == 0 ? a : a.slerp(u, motion.rotation(i1, j)));
    }
    const auto t0 = motion.translations(i0), t1 = motion.translations(i1);
    for (std::size_t s = 0; s < translated; ++s) translations.push_back(u == 0 ? t0[s] : ((1 - u) * t0[s] + u * t1[s]).eval());
  }
  return Motion(motion.sharedSkeleton(), 1.0 / fps, std::move(rotations), std::move(translations));
}

}  // namespace mgrl
