#include "inspect.hpp"

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "plural.hpp"

namespace mgrl::app {

std::string inspectText(const std::vector<FileReport>& reports) {
  std::string out;
  for (const FileReport& r : reports) {
    out += fmt::format("{}\n", r.path);
    out += fmt::format("  joints {}, frames {} at {:.4g} fps", r.joints, r.frames, r.fps);
    if (std::abs(r.fps - r.fileFps) > 1e-9) out += fmt::format(" (file: {:.4g} fps)", r.fileFps);
    out += fmt::format(", duration {:.2f} s\n", r.duration_s);
    std::vector<std::string> roles;
    for (const auto& [role, joint] : r.roles) roles.push_back(fmt::format("{}={}", role, joint));
    out += fmt::format("  roles: {}\n", fmt::join(roles, ", "));
    out += fmt::format("  joint names: {}\n", fmt::join(r.jointNames, " "));
    if (!r.rootMotion.empty()) out += fmt::format("  {}\n", r.rootMotion);
    out += fmt::format("  height {:.3f} m (file units: {}), ground at y = {:.3f} m\n", r.height_m, r.units, r.groundY_m);
    const double n = static_cast<double>(std::max<std::size_t>(1, r.frames));
    out += fmt::format("  foot contact frames: left {} ({:.0f}%), right {} ({:.0f}%)\n", r.contactFrames[0],
                       100.0 * static_cast<double>(r.contactFrames[0]) / n, r.contactFrames[1],
                       100.0 * static_cast<double>(r.contactFrames[1]) / n);
    out += fmt::format("  effective hits: left {} in {}, right {} in {}, total {}\n", r.hits[0],
                       counted(static_cast<std::size_t>(r.punches[0]), "punch", "punches"), r.hits[1], counted(static_cast<std::size_t>(r.punches[1]), "punch", "punches"),
                       r.hits[0] + r.hits[1]);
    if (r.hits[0] + r.hits[1] > 0) {
      out += fmt::format("  peak hit speed {:.2f} m/s\n", r.peakHitSpeed_mps);
      out += fmt::format("  hitting points, avatar frame (m): x [{:.2f}, {:.2f}] (left +), y [{:.2f}, {:.2f}], "
                         "z [{:.2f}, {:.2f}] (forward +)\n",
                         r.hitMin.x(), r.hitMax.x(), r.hitMin.y(), r.hitMax.y(), r.hitMin.z(), r.hitMax.z());
    }
    // Kicks only where there are some: a boxer's report reads as before.
    if (r.kickFrames[0] + r.kickFrames[1] > 0)
      out += fmt::format("  effective kicks: left {} in {}, right {} in {}; peak toe speed {:.2f} m/s, toe tips "
                         "y [{:.2f}, {:.2f}] m\n",
                         counted(r.kickFrames[0], "frame"), counted(static_cast<std::size_t>(r.kicks[0]), "kick"),
                         counted(r.kickFrames[1], "frame"), counted(static_cast<std::size_t>(r.kicks[1]), "kick"),
                         r.peakKickSpeed_mps, r.kickMin.y(), r.kickMax.y());
    if (!r.autoPunchSpeed.empty()) out += fmt::format("  {}\n", r.autoPunchSpeed);
    if (r.punchScale[0] < 1 || r.punchScale[1] < 1)
      out += fmt::format("  punch speed threshold {:.2f} / {:.2f} m/s (left / right): the fist tip found is the wrist or "
                         "near it, which moves slower than knuckles (scaled by {:.2f} / {:.2f})\n",
                         r.punchMinSpeed_mps[0], r.punchMinSpeed_mps[1], r.punchScale[0], r.punchScale[1]);
    if (r.swings[0] + r.swings[1] > 0)
      out += fmt::format(
          "  {} not counted as punches (the fist did not drive out from the body)\n",
          counted(static_cast<std::size_t>(r.swings[0]) + static_cast<std::size_t>(r.swings[1]), "arm swing"));
    if (r.glitchFrames > 0)
      out += fmt::format("  {} ignored (faster than the glitch threshold)\n",
                         counted(static_cast<std::size_t>(r.glitchFrames), "fist-speed glitch frame"));
    if (r.knockdownFrames > 0)
      out += fmt::format("  {} knocked down (head top below {:.0f} % of the standing height): no punches counted there\n",
                         counted(r.knockdownFrames, "frame"), 100 * r.knockdownRatio);
  }
  return out;
}

}  // namespace mgrl::app
