// The punch threshold chosen from a capture's own fist speeds (punch_min_speed_mps: auto):
// the Otsu split of the logarithms of every fist speed annotate() would weigh against it.
#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/annotation.hpp"

namespace mgrl {

double otsuThreshold(std::span<const double> values, double lo, double hi, int bins) {
  if (bins < 2 || !(hi > lo))
    throw Error(
        fmt::format("otsuThreshold: expected at least 2 bins over lo < hi, found {} over [{}, {}]", bins, lo, hi));
  const double width = (hi - lo) / bins;
  std::vector<double> count(static_cast<std::size_t>(bins), 0.0);
  for (double v : values) {
    const double bin = std::floor((v - lo) / width);
    count[static_cast<std::size_t>(std::clamp(bin, 0.0, static_cast<double>(bins - 1)))] += 1;
  }
  auto centre = [&](std::size_t i) { return lo + width * (static_cast<double>(i) + 0.5); };
  double total = 0, sum = 0;
  for (std::size_t i = 0; i < count.size(); ++i) {
    total += count[i];
    sum += count[i] * centre(i);
  }
  // Otsu (1979): the split k maximising w0 w1 (m0 - m1)^2, classes below and above edge k.
  // Empty bins between the classes give equal maxima: the middle of that gap.
  double w0 = 0, s0 = 0, best = 0;
  std::size_t first = 0, last = 0;
  for (std::size_t i = 0; i + 1 < count.size(); ++i) {
    w0 += count[i];
    s0 += count[i] * centre(i);
    const double w1 = total - w0;
    if (w0 == 0 || w1 == 0) continue;
    const double gap = s0 / w0 - (sum - s0) / w1;
    const double between = w0 * w1 * gap * gap;
    if (between > best * (1 + 1e-12)) {
      best = between;
      first = last = i + 1;
    } else if (best > 0 && between >= best * (1 - 1e-12)) {
      last = i + 1;
    }
  }
  return lo + width * 0.5 * static_cast<double>(first + last);
}

AutoPunchSpeed autoPunchMinSpeed(std::span<const Motion* const> motions, const SkeletonRoles& roles,
                                 const AnnotationParams& params) {
  // Every frame that annotate() would weigh against the threshold, with the threshold at
  // its floor and the body-drive test off.
  constexpr double kFloor_mps = 0.5, kCeiling_mps = 15.0;
  AnnotationParams sampling = params;
  sampling.punchMinSpeedAuto = false;
  sampling.punchMinSpeed_mps = kFloor_mps;
  sampling.punchMinBodySpeed_mps = 0;
  sampling.punchMaxSpeed_mps = std::max(params.punchMaxSpeed_mps, kFloor_mps + 1);
  std::vector<double> logSpeeds;
  for (const Motion* motion : motions) {
    const Annotation a = annotate(*motion, roles, sampling);
    for (const EffectiveHit& h : a.hits)
      logSpeeds.push_back(std::log(h.alongForearm_mps / a.punchScale[static_cast<int>(h.hand)]));
  }
  AutoPunchSpeed chosen;
  chosen.samples = logSpeeds.size();
  if (logSpeeds.size() < kAutoPunchMinSamples) {
    chosen.speed_mps = AnnotationParams{}.punchMinSpeed_mps;
    chosen.fellBack = true;
    return chosen;
  }
  const double split = std::exp(otsuThreshold(logSpeeds, std::log(kFloor_mps), std::log(kCeiling_mps), 400));
  chosen.speed_mps = std::clamp(split, kAutoPunchMin_mps, kAutoPunchMax_mps);
  chosen.clamped = chosen.speed_mps != split;
  return chosen;
}

std::string AutoPunchSpeed::sentence() const {
  if (fellBack)
    return fmt::format(
        "punch threshold auto: {:.2f} m/s, the default: {} fist speeds are too few to choose from "
        "(expected at least {})",
        speed_mps, samples, kAutoPunchMinSamples);
  return fmt::format("punch threshold auto: {:.2f} m/s, the Otsu split of {} fist speeds (log scale){}", speed_mps,
                     samples,
                     clamped ? fmt::format(", held within [{}, {}] m/s", kAutoPunchMin_mps, kAutoPunchMax_mps) : "");
}

}  // namespace mgrl
