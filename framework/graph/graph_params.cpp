#include "mgrl/graph/graph_params.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "mgrl/core/enum_words.hpp"
#include "mgrl/core/error.hpp"

namespace mgrl {

namespace {
constexpr std::array<EnumWord<ContactEvent>, 3> kContactEvents{{{ContactEvent::LeftFootLiftoff, "left_foot_liftoff"},
                                                                {ContactEvent::AnyContactChange, "any_contact_change"},
                                                                {ContactEvent::None, "none"}}};
}  // namespace

ContactEvent parseContactEvent(std::string_view text) { return parseWord(kContactEvents, text); }
std::string_view contactEventName(ContactEvent event) { return wordOf(kContactEvents, event); }

void GraphParams::validate() const {
  auto check = [](bool ok, std::string_view key, std::string_view expected, double found) {
    if (!ok) throw Error(fmt::format("graph.{}: expected {}, found {}", key, expected, found));
  };
  check(std::isfinite(threshold) && threshold > 0 && threshold <= 10, "threshold", "a distance in (0, 10]", threshold);
  check(std::isfinite(velocityWeight) && velocityWeight >= 0 && velocityWeight <= 10, "velocity_weight",
        "seconds in [0, 10]", velocityWeight);
  check(std::isfinite(rootHeightWeight) && rootHeightWeight >= 0 && rootHeightWeight <= 100, "root_height_weight",
        "a weight in [0, 100]", rootHeightWeight);
  check(blendFrames >= 0 && blendFrames <= 120, "blend_frames", "a frame count in [0, 120]", blendFrames);
  check(minStates >= 1 && minStates <= 1000000, "min_states", "a count in [1, 1000000]", minStates);
  check(threads <= 256, "threads", "a thread count in [0, 256]", threads);
  if (maxOutDegree)
    check(*maxOutDegree == 0 || (*maxOutDegree >= 2 && *maxOutDegree <= 100000), "max_out_degree",
          "auto, 0 (no bound) or an action count in [2, 100000]", *maxOutDegree);
  for (const auto& [name, weight] : jointWeights)
    if (!std::isfinite(weight) || weight < 0 || weight > 100)
      throw Error(fmt::format("graph.joint_weights.{}: expected a weight in [0, 100], found {}", name, weight));
}

int GraphParams::outDegreeFor(double captureSeconds) const {
  if (maxOutDegree) return *maxOutDegree;
  return captureSeconds > kLibrarySeconds ? kLibraryOutDegree : 0;
}

bool GraphParams::standingCutsFor(double captureSeconds) const {
  if (standingCuts) return *standingCuts;
  return captureSeconds > kLibrarySeconds;
}

double defaultJointWeight(std::string_view jointName) {
  std::string name(jointName);
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  auto has = [&](std::string_view part) { return name.find(part) != std::string::npos; };
  if (has("finger") || has("thumb") || has("index") || has("middle") || has("ring") || has("pinky") ||
      has("hand_end") || has("handend"))
    return 0;
  if (has("hand") || has("wrist")) return 0.3;
  if (has("toe")) return 0.3;
  if (has("head")) return 0.3;
  if (has("foot") || has("ankle") || has("neck") || has("shoulder") || has("clavicle") || has("collar")) return 0.5;
  return 1;
}

}  // namespace mgrl
