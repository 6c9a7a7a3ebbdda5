// Real bouts to learn from: the SNU sparring capture's files grouped into bouts,
// and the facing angle each fighter keeps to the other (as `mgrl stats` measures it).
#include "mgrl/learning/real_bouts.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl {
namespace fs = std::filesystem;

std::vector<BoutFiles> snuBouts(const fs::path& dataDir) {
  const fs::path dir = dataDir / "snu_martial_arts" / "motion";
  std::map<std::string, std::vector<fs::path>> groups;
  std::error_code ec;
  if (fs::is_directory(dir, ec))
    for (const auto& item : fs::directory_iterator(dir, ec)) {
      const std::string file = item.path().filename().string();
      // s_TTT_K_P.bvh: the bout is s_TTT_K, the fighter P.
      if (!item.is_regular_file(ec) || ::fnmatch("s_*_*_*.bvh", file.c_str(), 0) != 0) continue;
      groups[file.substr(0, file.rfind('_'))].push_back(item.path());
    }
  if (groups.empty())
    throw Error(
        fmt::format("expected the SNU sparring capture s_TTT_K_P.bvh in {}, found none (set --data or "
                    "MGRL_DATA)",
                    dir.string()));
  std::vector<BoutFiles> bouts;
  for (auto& [name, files] : groups) {
    std::sort(files.begin(), files.end());
    bouts.push_back({name, files});
  }
  return bouts;
}

double facingDegrees(const Eigen::Vector2d& facing, const Eigen::Vector2d& toOther, double distance) {
  return std::acos(std::clamp(facing.dot(toOther) / distance, -1.0, 1.0)) * 180 / std::numbers::pi;
}

namespace {

// One fighter's facing (unit, on the ground) and pelvis (on the ground) per frame.
struct Track {
  std::vector<Eigen::Vector2d> facing, pelvis;
};

Track trackOf(const Motion& motion, std::size_t frames, const std::string& source) {
  const SkeletonRoles roles = findRoles(motion.skeleton(), {}, source, {});
  const Annotation annotation = annotate(motion, roles, {});
  const auto pelvis = static_cast<std::size_t>(roles.pelvis);
  Track track;
  track.facing.reserve(frames);
  track.pelvis.reserve(frames);
  std::vector<Eigen::Quaterniond> rotations(motion.skeleton().jointCount());
  std::vector<Eigen::Vector3d> positions(motion.skeleton().jointCount());
  for (std::size_t f = 0; f < frames; ++f) {
    forwardKinematics(motion, f, rotations, positions);
    const double yaw = annotation.frames[f].yaw;  // atan2(x, z) of the facing axis
    track.facing.emplace_back(std::sin(yaw), std::cos(yaw));
    track.pelvis.emplace_back(positions[pelvis].x(), positions[pelvis].z());
  }
  return track;
}

}  // namespace

std::vector<double> boutFacingDegrees(const std::vector<BoutFiles>& bouts) {
  std::vector<double> degrees;
  for (const BoutFiles& bout : bouts) {
    if (bout.files.size() < 2)
      throw Error(
          fmt::format("bout {}: expected at least 2 fighters (BVH files), found {}", bout.name, bout.files.size()));
    std::vector<LoadedMotion> loaded;
    std::size_t frames = std::numeric_limits<std::size_t>::max();
    for (const fs::path& file : bout.files) {
      loaded.push_back(loadMotion(file));
      const double t0 = loaded.front().motion.frameTime(), t = loaded.back().motion.frameTime();
      if (std::abs(t - t0) > 1e-6 * t0)
        throw Error(
            fmt::format("bout {}: expected one frame time for all fighters, found {:.6g} s in {} and {:.6g} "
                        "s in {}",
                        bout.name, t0, bout.files.front().string(), t, file.string()));
      frames = std::min(frames, loaded.back().motion.frameCount());
    }
    std::vector<Track> tracks;
    for (std::size_t i = 0; i < loaded.size(); ++i)
      tracks.push_back(trackOf(loaded[i].motion, frames, bout.files[i].string()));
    for (std::size_t i = 0; i < tracks.size(); ++i)
      for (std::size_t f = 0; f < frames; ++f) {
        // The nearest other fighter (a two-fighter bout: the other one).
        Eigen::Vector2d toOther = Eigen::Vector2d::Zero();
        double nearest = std::numeric_limits<double>::infinity();
        for (std::size_t j = 0; j < tracks.size(); ++j) {
          const Eigen::Vector2d d = tracks[j].pelvis[f] - tracks[i].pelvis[f];
          if (j != i && d.norm() < nearest) {
            nearest = d.norm();
            toOther = d;
          }
        }
        if (nearest > 1e-9) degrees.push_back(facingDegrees(tracks[i].facing[f], toOther, nearest));
      }
  }
  return degrees;
}

std::vector<double> facingStances(std::vector<double> degrees, int count) {
  if (count < 1 || degrees.size() < static_cast<std::size_t>(count))
    throw Error(
        fmt::format("expected at least as many facing samples as stances ({}), found {}", count, degrees.size()));
  std::sort(degrees.begin(), degrees.end());
  std::vector<double> stances;
  const std::size_t n = degrees.size(), parts = static_cast<std::size_t>(count);
  for (std::size_t k = 0; k < parts; ++k) {
    const std::size_t begin = k * n / parts, end = (k + 1) * n / parts;  // [begin, end), not empty
    const std::size_t middle = begin + (end - begin) / 2;
    stances.push_back((end - begin) % 2 == 1 ? degrees[middle] : 0.5 * (degrees[middle - 1] + degrees[middle]));
  }
  return stances;
}

const std::vector<double>& snuFacingDegrees(const fs::path& dataDir) {
  static std::mutex mutex;
  static std::map<fs::path, std::vector<double>> read;
  const std::lock_guard<std::mutex> lock(mutex);
  const fs::path key = dataDir.lexically_normal();
  if (auto found = read.find(key); found != read.end()) return found->second;
  return read.emplace(key, boutFacingDegrees(snuBouts(dataDir))).first->second;
}

}  // namespace mgrl
