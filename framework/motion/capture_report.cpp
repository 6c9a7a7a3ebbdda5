#include "mgrl/motion/capture_report.hpp"

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/numbers.hpp"

namespace mgrl {

FileReport inspectFile(const std::filesystem::path& path, const InspectOptions& options) {
  const LoadedMotion loaded = loadMotion(path, options.load);
  RootMotionReport rootMotion;
  const SkeletonRoles fileRoles = findRoles(loaded.motion.skeleton(), options.roles, path.string(), options.load.warn);
  const Motion motion = moveRootToPelvis(loaded.motion, fileRoles.pelvis, path.string(), rootMotion);
  const SkeletonRoles roles =
      fileRoles.pelvis == 0 ? fileRoles : findRoles(motion.skeleton(), options.roles, path.string());
  // `--punch-min-speed auto`: chosen from this file's own fist speeds.
  AnnotationParams params = options.annotation;
  std::string autoPunch;
  if (params.punchMinSpeedAuto) {
    const Motion* const one[] = {&motion};
    const AutoPunchSpeed chosen = autoPunchMinSpeed(one, roles, params);
    params.punchMinSpeed_mps = chosen.speed_mps;
    params.punchMinSpeedAuto = false;
    autoPunch = chosen.sentence();
  }
  const Annotation annotation = annotate(motion, roles, params);
  if (const std::string unusual = unusualHeightWarning(annotation, path.string());
      !unusual.empty() && options.load.warn)
    options.load.warn(unusual);

  FileReport report;
  report.path = path.string();
  report.joints = motion.skeleton().jointCount();
  for (const Joint& joint : motion.skeleton().joints()) report.jointNames.push_back(joint.name);
  const std::vector<std::string> roleNameList = roleNames();
  const std::vector<int> roleJoints = roleJointIndices(roles);
  for (std::size_t r = 0; r < roleNameList.size(); ++r)
    report.roles.emplace_back(roleNameList[r], roleJoints[r] >= 0 ? report.jointNames[roleJoints[r]] : "");
  report.frames = motion.frameCount();
  report.fps = motion.fps();
  report.fileFps = loaded.fileFps;
  report.duration_s = motion.duration();
  report.height_m = annotation.standingHeight;
  report.restHeight_m = roles.restHeight;
  report.rootMotionJoint = rootMotion.jointName;
  if (rootMotion.joint != 0) report.rootMotion = rootMotion.sentence;
  report.knockdownFrames = annotation.knockdownFrames;
  report.knockdownRatio = options.annotation.knockdownHeadRatio;
  report.groundY_m = annotation.groundY;
  report.units = std::string(lengthUnitName(loaded.units));
  report.glitchFrames = annotation.glitchFrames;
  report.punches = annotation.punches;
  report.swings = annotation.swings;
  report.punchScale = annotation.punchScale;
  for (int s = 0; s < 2; ++s) report.punchMinSpeed_mps[s] = params.punchMinSpeed_mps * annotation.punchScale[s];
  report.autoPunchSpeed = autoPunch;
  for (int s = 0; s < 2; ++s) {
    report.contactFrames[s] = annotation.contactFrames(static_cast<Side>(s));
    report.hits[s] = annotation.hitCount(static_cast<Side>(s));
  }
  if (!annotation.hits.empty()) {
    report.hitMin = report.hitMax = annotation.hits.front().tipAvatar;
    for (const EffectiveHit& hit : annotation.hits) {
      report.hitMin = report.hitMin.cwiseMin(hit.tipAvatar);
      report.hitMax = report.hitMax.cwiseMax(hit.tipAvatar);
      report.peakHitSpeed_mps = std::max(report.peakHitSpeed_mps, hit.speed_mps);
    }
  }
  report.kicks = annotation.kickCount;
  if (!annotation.kicks.empty()) report.kickMin = report.kickMax = annotation.kicks.front().tipAvatar;
  for (const EffectiveHit& kick : annotation.kicks) {
    ++report.kickFrames[static_cast<int>(kick.hand)];
    report.kickMin = report.kickMin.cwiseMin(kick.tipAvatar);
    report.kickMax = report.kickMax.cwiseMax(kick.tipAvatar);
    report.peakKickSpeed_mps = std::max(report.peakKickSpeed_mps, kick.speed_mps);
  }
  return report;
}

nlohmann::json inspectJson(const std::vector<FileReport>& reports) {
  nlohmann::json files = nlohmann::json::array();
  for (const FileReport& r : reports) {
    auto vec = [](const Eigen::Vector3d& v) {
      return nlohmann::json::array({rounded(v.x(), 4), rounded(v.y(), 4), rounded(v.z(), 4)});
    };
    files.push_back({
        {"path", r.path},
        {"joints", r.joints},
        {"joint_names", r.jointNames},
        {"roles",
         [&] {
           nlohmann::json roles = nlohmann::json::object();
           for (const auto& [role, joint] : r.roles) roles[role] = joint;
           return roles;
         }()},
        {"frames", r.frames},
        {"fps", rounded(r.fps, 6)},
        {"file_fps", rounded(r.fileFps, 6)},
        {"duration_s", rounded(r.duration_s, 6)},
        {"height_m", rounded(r.height_m, 4)},
        {"rest_height_m", rounded(r.restHeight_m, 4)},
        {"root_motion_joint", r.rootMotionJoint},
        {"units", r.units},
        {"ground_y_m", rounded(r.groundY_m, 4)},
        {"contact_frames", {{"left", r.contactFrames[0]}, {"right", r.contactFrames[1]}}},
        {"effective_hits", {{"left", r.hits[0]}, {"right", r.hits[1]}, {"total", r.hits[0] + r.hits[1]}}},
        {"punches", {{"left", r.punches[0]}, {"right", r.punches[1]}, {"total", r.punches[0] + r.punches[1]}}},
        {"arm_swings", r.swings[0] + r.swings[1]},
        {"punch_min_speed_mps", {rounded(r.punchMinSpeed_mps[0], 3), rounded(r.punchMinSpeed_mps[1], 3)}},
        {"punch_min_speed_auto", r.autoPunchSpeed.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.autoPunchSpeed)},
        {"peak_hit_speed_mps", rounded(r.peakHitSpeed_mps, 3)},
        {"effective_kick_frames",
         {{"left", r.kickFrames[0]}, {"right", r.kickFrames[1]}, {"total", r.kickFrames[0] + r.kickFrames[1]}}},
        {"kicks", {{"left", r.kicks[0]}, {"right", r.kicks[1]}, {"total", r.kicks[0] + r.kicks[1]}}},
        {"peak_kick_speed_mps", rounded(r.peakKickSpeed_mps, 3)},
        {"kick_bounds_m", r.kickFrames[0] + r.kickFrames[1] == 0
                              ? nlohmann::json(nullptr)
                              : nlohmann::json{{"min", vec(r.kickMin)}, {"max", vec(r.kickMax)}}},
        {"glitch_frames", r.glitchFrames},
        {"knockdown_frames", r.knockdownFrames},
        {"hit_bounds_m", r.hits[0] + r.hits[1] == 0 ? nlohmann::json(nullptr)
                                                    : nlohmann::json{{"min", vec(r.hitMin)}, {"max", vec(r.hitMax)}}},
    });
  }
  return {{"files", files}};
}

}  // namespace mgrl
