#pragma once
/// \file
/// Real bouts as a source to learn from: which files make the SNU sparring
/// capture's bouts, and the facing angles its fighters keep to each other. `mgrl stats`
/// (runtime/bout_report) measures bouts; the `facing` reward term's `prefer: bouts` learns
/// the distribution of the facing angle from them.
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mgrl {

/// A bout's name and files (one BVH per fighter, one world frame), before loading.
struct BoutFiles {
  std::string name;
  std::vector<std::filesystem::path> files;
};

/// Every real SNU sparring bout: snu_martial_arts/motion/s_TTT_K_P.bvh under `dataDir`,
/// grouped by TTT_K (the fighters P of one bout). Throws mgrl::Error if there is none (the
/// message names no option: callers say which of theirs asked).
std::vector<BoutFiles> snuBouts(const std::filesystem::path& dataDir);

/// The facing `mgrl stats` reports: the angle on the ground between a unit `facing` and the
/// direction `toOther` of length `distance` (> 0), in degrees in [0, 180].
double facingDegrees(const Eigen::Vector2d& facing, const Eigen::Vector2d& toOther, double distance);

/// For every fighter and frame of `bouts`: the angle on the ground between the fighter's
/// facing (the annotation's yaw) and the direction to the nearest other fighter's pelvis,
/// in degrees in [0, 180] (frames with the pelvises together are left out). This is the
/// facing `mgrl stats` reports. A bout is read up to its shortest fighter's last frame.
/// Throws mgrl::Error for unreadable files, bouts of fewer than two fighters or fighters
/// with different frame times.
std::vector<double> boutFacingDegrees(const std::vector<BoutFiles>& bouts);

/// Stances learned from facing samples: the samples sorted and cut into `count`
/// equally large parts, the median of each, in increasing order. Throws mgrl::Error for
/// fewer samples than parts or a count below 1.
std::vector<double> facingStances(std::vector<double> degrees, int count);

/// boutFacingDegrees(snuBouts(dataDir)), read once per data folder and process (the
/// capture is about 7 MB; every behaviour with such a term would read it again).
const std::vector<double>& snuFacingDegrees(const std::filesystem::path& dataDir);

}  // namespace mgrl
