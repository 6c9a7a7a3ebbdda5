#pragma once
/// \file
/// The viewer protocol (docs/viewer-protocol.md): the page's messages, checked field by
/// field before anything acts on them, and the binary pose frame the server sends.
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <Eigen/Core>

namespace mgrl::serve {

/// Limits of the protocol (docs/viewer-protocol.md), shared by the server and its tests.
struct Limits {
  static constexpr std::size_t kMessageBytes = 4096;   ///< largest page message
  static constexpr int kMessagesPerSecond = 200;       ///< more within one second: closed
  static constexpr int kCrowdMin = 2, kCrowdMax = 2000, kCrowdDefault = 30;
  static constexpr double kTargetReach = 100;          ///< |x|, |z| of a target, m
  static constexpr double kTargetHeightMax = 3;        ///< m
  static constexpr int kHorizonMax = 5;                ///< online search, actions
  static constexpr double kWeightMax = 10;
  static constexpr double kSpeedMin = 0.1, kSpeedMax = 4;
  static constexpr int kMaxSessions = 16;
  // The learn panel (Q-learning stepped on the page).
  static constexpr int kLearnBudgetMax = 10'000'000;  ///< actions; alpha falls from 1 over the budget
  static constexpr int kLearnBudgetDefault = 20'000;
  static constexpr int kLearnStepsMax = 1000;         ///< per `step` message
  static constexpr double kLearnRateMax = 2000;       ///< steps per second while running
  static constexpr double kLessonBytes = 64e6;        ///< one page's lesson table, at most
  // Live retraining.
  static constexpr int kRetrainKeysMax = 8;
};

enum class Mode { Target, Sparring, Crowd };
const char* modeName(Mode mode);

struct SetMode {
  Mode mode = Mode::Target;
  int avatars = 1;
};
struct MoveTarget {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};
struct SetController {
  std::string controller;
  int horizon = 0;  ///< 0: unchanged
};
struct SetWeights {
  std::map<std::string, double> weights;
};
struct Pause {
  bool paused = false;
};
struct Step {};
struct SetSpeed {
  double speed = 1;
};
/// The teaching view: stream a behaviour's values around avatar 0 ("" stops).
struct ShowValues {
  std::string behavior;
};

/// The learn panel: Q-learning (paper sec. 4.2) on one behaviour's problem, a step at a
/// time, from an all-zero table of the page's own.
struct Learn {
  enum class Command { Start, Step, Run, Stop };
  Command command = Command::Step;
  std::string behavior;  ///< start
  std::uint64_t seed = 1;  ///< start
  std::uint64_t budget = Limits::kLearnBudgetDefault;  ///< start
  int steps = 1;         ///< step
  double rate = 0;       ///< run: steps per second (0 pauses)
};
/// Live retraining: value iteration on one behaviour with some of its reward's or grid's
/// parameters changed ("reward.sigma", "discretizer.angles"); none: back to the policy
/// bundle's table.
struct Retrain {
  std::string behavior;
  std::map<std::string, double> set;
  /// The keys whose number was written with a fraction or an exponent (3.0, 1e3), as the
  /// page wrote it: a whole-number parameter refuses them (as `avatars` does).
  std::map<std::string, std::string> fractional;
};

using ClientMessage =
    std::variant<SetMode, MoveTarget, SetController, SetWeights, Pause, Step, SetSpeed, ShowValues, Learn, Retrain>;

/// Parses and checks one page message. Throws mgrl::Error whose text says which field was
/// expected to hold what and what it held (the server sends it back as an `error`).
/// `controllers`: the names a `controller` message may choose (the session's registry's,
/// ControllerRegistry::names()); behaviour names are checked by the session, which knows them.
ClientMessage parseClientMessage(std::string_view text, const std::vector<std::string>& controllers);

/// The binary pose frame (docs/viewer-protocol.md), appended to `out` after clearing it.
struct FrameHeader {
  std::uint16_t joints = 0;
  std::uint32_t avatars = 0, targets = 0, frame = 0;
  float time = 0;
};
constexpr std::size_t kFrameHeaderBytes = 24;
constexpr std::size_t avatarRecordBytes(std::size_t joints) { return 12 + 6 * joints; }
constexpr std::size_t kTargetRecordBytes = 16;

class FrameWriter {
 public:
  /// Starts a frame of `header.avatars` avatars and `header.targets` targets.
  void begin(const FrameHeader& header);
  /// One avatar: its joints' world positions (the root first).
  void avatar(std::span<const Eigen::Vector3d> joints);
  void target(std::uint32_t avatar, const Eigen::Vector3d& centre);
  /// The finished frame; throws mgrl::Error if fewer or more records were written than
  /// the header announced.
  const std::vector<std::uint8_t>& finish();

 private:
  void put(const void* bytes, std::size_t n);
  std::vector<std::uint8_t> bytes_;
  FrameHeader header_;
  std::uint32_t avatarsWritten_ = 0, targetsWritten_ = 0;
};

/// Reads a frame back (for tests and tools): every joint position in world metres, per
/// avatar, and the targets. Throws mgrl::Error for a frame whose sizes do not add up.
struct DecodedFrame {
  FrameHeader header;
  std::vector<std::vector<Eigen::Vector3d>> avatars;
  std::vector<std::pair<std::uint32_t, Eigen::Vector3d>> targets;
};
DecodedFrame decodeFrame(std::span<const std::uint8_t> bytes);

}  // namespace mgrl::serve
