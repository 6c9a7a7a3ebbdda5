#pragma once
/// \file
/// What is in a motion file (joints, roles, frames, duration, height, root motion,
/// contacts, effective punches and kicks), as `mgrl inspect` and Python's mgrl.inspect
/// report it: what a user checks first when bringing capture of their own.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/motion/roles.hpp"
#include "mgrl/motion/root_motion.hpp"

namespace mgrl {

struct InspectOptions {
  std::vector<std::filesystem::path> files;
  LoadOptions load;
  RoleOverrides roles;
  AnnotationParams annotation;
};

/// Everything inspect reports about one file.
struct FileReport {
  std::string path;
  std::size_t joints = 0, frames = 0;
  /// The names a reward term's body point may use (scenarios/README.md, body points): the
  /// skeleton's joints, and each role with the joint that plays it.
  std::vector<std::string> jointNames;
  std::vector<std::pair<std::string, std::string>> roles;
  double fps = 0, fileFps = 0, duration_s = 0, groundY_m = 0;
  double height_m = 0;          ///< standing height from the motion (Annotation::standingHeight)
  double restHeight_m = 0;      ///< from the rest pose (SkeletonRoles::restHeight)
  std::string rootMotionJoint;  ///< the joint the travel is taken from (root_motion.hpp)
  std::string rootMotion;       ///< a sentence when that is not the file's root, else empty
  std::string units;
  std::array<std::size_t, 2> contactFrames{}, hits{};
  std::array<int, 2> punches{};
  std::array<int, 2> swings{};
  std::array<double, 2> punchMinSpeed_mps{};  ///< the threshold used per hand (scaled for a wrist)
  std::string autoPunchSpeed;  ///< what `--punch-min-speed auto` chose (AutoPunchSpeed::sentence()), else empty
  std::array<double, 2> punchScale{1.0, 1.0};  ///< Annotation::punchScale
  int glitchFrames = 0;
  std::size_t knockdownFrames = 0;  ///< frames with no punch counted: the boxer is down
  double knockdownRatio = 0;        ///< AnnotationParams::knockdownHeadRatio used
  double peakHitSpeed_mps = 0;
  /// Effective kicks (Annotation::kicks): frames and kicks per foot, peak toe speed, and
  /// the toe tips' bounds in the avatar frame.
  std::array<std::size_t, 2> kickFrames{};
  std::array<int, 2> kicks{};
  double peakKickSpeed_mps = 0;
  Eigen::Vector3d kickMin = Eigen::Vector3d::Zero(), kickMax = Eigen::Vector3d::Zero();
  Eigen::Vector3d hitMin = Eigen::Vector3d::Zero(), hitMax = Eigen::Vector3d::Zero();
};

/// Loads, annotates and summarises one file. Warnings (a fist standing in for a missing
/// one, an unusual standing height) go to options.load.warn. Throws mgrl::Error on bad input.
FileReport inspectFile(const std::filesystem::path& path, const InspectOptions& options);

/// {"files": [...]}: `mgrl inspect --json`'s report (docs list the keys in README.md).
nlohmann::json inspectJson(const std::vector<FileReport>& reports);

}  // namespace mgrl
