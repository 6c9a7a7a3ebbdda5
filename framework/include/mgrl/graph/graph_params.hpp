#pragma once
/// \file
/// Parameters of motion-graph construction: a scenario's `graph:` section
/// (scenarios/README.md explains each key and its default).
#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace mgrl {

/// Which frames may be joined by a transition (Lee & Lee 2004, sec. 6.3): only frames at
/// the same contact event.
enum class ContactEvent : unsigned char {
  LeftFootLiftoff,   ///< the paper's choice: the last frame of a left-foot contact
  AnyContactChange,  ///< the last frame before any foot lifts off or touches down (same kind on both sides)
  None,              ///< every frame
};
ContactEvent parseContactEvent(std::string_view text);  ///< throws mgrl::Error listing the names
std::string_view contactEventName(ContactEvent event);

struct GraphParams {
  /// A transition i -> j needs the distance between frame i and frame j - 1 below this.
  /// The distance is a weighted RMS joint-angle difference (radians) plus the velocity
  /// and root-height terms below, so 0.45 means "joints about 26 degrees apart on average".
  double threshold = 0.45;
  /// Seconds: a joint angular-velocity difference of w rad/s counts like an angle
  /// difference of velocityWeight * w radians (Lee et al. 2002's nu). 0 ignores velocities.
  double velocityWeight = 0.1;
  /// Radians per metre: how much a difference in pelvis height above the ground counts.
  double rootHeightWeight = 1.0;
  ContactEvent contactEvent = ContactEvent::LeftFootLiftoff;
  /// Keep only transitions that are local minima of the distance among neighbouring
  /// candidate frames (Lee et al. 2002), so near-duplicate transitions collapse to one.
  bool localMinimum = true;
  /// Frames over which an action entering through a transition blends away the pose
  /// difference at playback.
  int blendFrames = 6;
  /// The largest strongly connected component must keep at least this many states.
  int minStates = 10;
  /// Per-joint weights by exact joint name, overriding the defaults (defaultJointWeight).
  std::map<std::string, double, std::less<>> jointWeights;
  /// Worker threads for the distance computation; 0: all cores.
  unsigned threads = 0;
  /// At most this many actions leave a state: each frame keeps its transitions of smallest
  /// distance, and transitions dropped this way come back where the component would
  /// otherwise lose frames. 0: no bound. Unset (`auto`): kLibraryOutDegree for a capture
  /// longer than kLibrarySeconds, none for a shorter one (the paper's scenarios).
  std::optional<int> maxOutDegree;
  /// Cut points also where the performer stands still: inside stretches of both feet
  /// planted, the frames where the whole body moves least (local minima of the joints'
  /// angular speed, at least kStandingCutSpacing_s apart) may join each other, so clips of
  /// gestures and standing, without a foot lift-off, join the graph. Unset (`auto`): on for
  /// a capture longer than kLibrarySeconds.
  std::optional<bool> standingCuts;

  static constexpr double kLibrarySeconds = 600;
  static constexpr int kLibraryOutDegree = 32;
  static constexpr double kStandingCutSpacing_s = 0.5;
  /// maxOutDegree and standingCuts for a capture of this many seconds (`auto` resolved).
  int outDegreeFor(double captureSeconds) const;
  bool standingCutsFor(double captureSeconds) const;

  /// Throws mgrl::Error naming the first out-of-range value (as its YAML key).
  void validate() const;
};

/// Default weight of a joint by its name: fingers and thumbs 0, hands 0.3, toes 0.3, feet,
/// neck and shoulders (clavicles) 0.5, head 0.3, everything else (pelvis, spine, arms,
/// legs) 1.
double defaultJointWeight(std::string_view jointName);

}  // namespace mgrl
