#pragma once
/// \file
/// What `mgrl serve` runs for each page (docs/viewer-protocol.md): a world of its own
/// (paper sec. 6.6: one boxer and a target the user drags; sec. 6.7: sparring pairs, a
/// crowd of them), its controller switched live, and the messages and pose frames the
/// page is sent. Knows nothing of sockets: the server calls it.
#include <chrono>
#include <deque>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "builtin_plugins.hpp"
#include "mgrl/session/policy_source.hpp"
#include "serve/protocol.hpp"

namespace mgrl {
class World;
struct QStep;
}

namespace mgrl::serve {

/// The session's options (with the built-in plug-ins) and the viewer's.
struct ServeOptions : SessionOptions {
  ServeOptions() { plugins = &builtinPlugins(); }
  std::filesystem::path policy;  ///< "" the scenario's default bundle, if trained
  /// The scenario whose behaviours play sparring and crowds: "" the scenario's
  /// own `sparring_scenario:` if it names one, "none" the scenario's own behaviours, else
  /// a scenario file. Its default bundle is used; of the --set flags only `world.` ones
  /// apply to it.
  std::string sparringScenario;
  /// The second avatar of each sparring pair plays this bundle's tables
  /// (greedily), the first the page's controller ("" both play the page's controller).
  std::filesystem::path partnerPolicy;
  int partnerRound = 0;  ///< > 0: that self-play round's tables of partnerPolicy
};

/// Everything the sessions share, loaded once: the graph, the behaviours, the policy
/// bundle (if any), the body table. Read-only once made.
struct ViewerAssets;
struct PageChoices;
std::shared_ptr<const ViewerAssets> loadViewerAssets(const ServeOptions& options);

/// Waits until no worker thread runs: retrainings (pages that left ask theirs to stop;
/// each stage of a retraining checks) and worlds being built. The server calls it when it
/// stops, so that none outlives it.
void waitForWorkers();

/// The server's time as a page shares it (docs/viewer-protocol.md, "Limits and
/// fairness"), for its `stats`.
struct PageShare {
  double secondsPerSecond = 0;  ///< this page's share of the network thread
  int pages = 1;
  std::size_t ticksSkipped = 0, ticks = 0;  ///< since the last stats
  /// Messages of the page that waited for its share or for another page's costly message
  /// to end before they were handled, and how long, s, since the last stats.
  std::size_t messagesWaited = 0;
  double waitedSeconds = 0;
};

/// No slice: advance() runs every frame it is asked for.
inline constexpr double kNoSlice = std::numeric_limits<double>::infinity();

/// One page's world and clock.
class ViewerSession {
 public:
  explicit ViewerSession(std::shared_ptr<const ViewerAssets> assets);
  ~ViewerSession();
  ViewerSession(const ViewerSession&) = delete;
  ViewerSession& operator=(const ViewerSession&) = delete;

  /// Builds the worlds of changes of mode on a thread of their own: a crowd's world touches
  /// megabytes of fresh memory (2,000 avatars: 18 MB, about 90 ms of page faults here),
  /// which would hold the server's one network thread. Off (the default), handle() builds
  /// them at once.
  void buildInBackground(bool on) { background_ = on; }
  /// Whether `text` may be handled now: not while this page's new world is being built,
  /// nor a change of mode while another page's is (one world is built at a time).
  bool ready(std::string_view text) const;
  /// Installs the world built in the background once it is done (or says why it failed):
  /// true if it did, and the page has a new scene and frame.
  bool poll();

  /// Acts on one page message (text). Refusals (mgrl::Error) are answered with an `error`
  /// message in the outbox and change nothing.
  void handle(std::string_view text);
  /// What handling `text` is expected to take of the server's thread, s, before it runs:
  /// a mode or crowd switch by the avatars of the world it replaces and of the new one, a
  /// lesson's or retraining's start by what the last such start took on this server (0.1 s,
  /// the most a page may spend at once, before one has run); 0 for messages that cost
  /// little (they are measured as they run) and for malformed ones.
  double price(std::string_view text) const;
  /// Advances the world by `frames` frames of its clock times the speed (fractions carry
  /// over); nothing while paused unless a step was asked for. True if it moved. Once
  /// `sliceSeconds` have gone on simulating (after the first frame), the frames still due
  /// are dropped, not carried: a heavy world then runs slower instead of holding the
  /// server's one thread (`stats.frames_shed` counts them).
  bool advance(double frames, double sliceSeconds = kNoSlice);
  /// The pose frame of now.
  const std::vector<std::uint8_t>& frame();
  /// The `stats` message, with the transport's frame counters and the page's share (the
  /// session's own counters restart).
  std::string stats(std::size_t framesSent, std::size_t framesDropped, const PageShare& share = {});
  /// Text messages waiting to be sent (scene, hits, errors), oldest first; cleared.
  std::vector<std::string> takeOutbox();

  /// The world's frame time, s.
  double frameTime() const;
  Mode mode() const { return mode_; }
  std::size_t avatars() const;

 private:
  struct State;
  /// Acts on a parsed message; throws mgrl::Error to refuse it.
  void handle(const ClientMessage& message);
  /// A new world of `avatars` in `mode`, built at once or in the background.
  void rebuild(Mode mode, int avatars);
  /// Makes `world`, playing `assets`' behaviours in `mode`, the page's world.
  /// `started`: the world has run its first frame (a background build runs it).
  void install(std::unique_ptr<World> world, Mode mode, std::shared_ptr<const ViewerAssets> assets,
               bool started = false);
  void applyController();
  /// The controllers the page may choose: those of the session `mgrl serve` opened
  /// (ServeOptions::plugins).
  const ControllerRegistry& controllers() const;
  /// The page's choices now, and what adopting `assets` would make of them.
  PageChoices choices() const;
  PageChoices choicesAfterAdopting(const ViewerAssets& assets) const;
  /// After each frame: plays every decision the frame made through the avatar's success
  /// trackers and counts the successes (the `stats` message's `successes`).
  void followSuccess();
  std::string scene() const;
  std::string slowed(const PageShare& share) const;
  /// The index of the behaviour called `name`, or -1; the names, comma-separated.
  int behaviorIndex(std::string_view name) const;
  std::string behaviorNames() const;
  /// The `values` message of the behaviour shown (docs/viewer-protocol.md).
  std::string values() const;
  /// The learn panel (Q-learning a step at a time) and live retraining.
  void learn(const Learn& message);
  void retrain(const Retrain& message);
  /// Runs the lesson at its rate and takes a finished retraining, with their messages.
  void advanceLesson(double frames);
  void collectRetraining();
  std::string lessonMessage() const;
  std::string stepMessage(const QStep& step, std::size_t taken) const;

  /// Makes `assets` the ones the page plays (the scenario's, or its sparring scenario's):
  /// weights, policy, controller and teaching views start again from them.
  void adopt(std::shared_ptr<const ViewerAssets> assets);

  std::shared_ptr<const ViewerAssets> root_;    ///< the scenario `mgrl serve` opened
  std::shared_ptr<const ViewerAssets> assets_;  ///< what the page plays now: root_ or root_->sparring
  std::unique_ptr<State> state_;
  Mode mode_ = Mode::Target;
  bool background_ = false;
  std::vector<std::string> outbox_;
};

}  // namespace mgrl::serve
