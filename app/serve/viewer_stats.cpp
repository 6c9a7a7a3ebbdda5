// What a page measures of its world: the successes its success criteria count, decision by
// decision (followSuccess), and the `stats` message (docs/viewer-protocol.md). Apart from
// viewer.cpp, which steps and switches the world.
#include <algorithm>
#include <cstdint>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mgrl/learning/success.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/session/session.hpp"
#include "serve/protocol.hpp"
#include "serve/viewer_parts.hpp"

namespace mgrl::serve {

using json = nlohmann::json;

void ViewerSession::followSuccess() {
  State& s = *state_;
  const World& world = *s.world;
  const StateActionModel& model = assets_->model();
  // A scripted opponent or a partner bundle plays the second of each pair, not the page's controller.
  const bool partnerApart = !assets_->session->partnerName(assets_->played).empty();
  const TrackedOpponent* opponent = assets_->session->task.trackedOpponent;
  for (std::size_t i = 0; i < world.avatarCount(); ++i) {
    if (partnerApart && world.partner(i) >= 0 && i % 2 == 1) continue;
    const World::Decision d = world.lastDecision(i);
    if (d.count == s.decisionsFollowed[i]) continue;
    s.decisionsFollowed[i] = d.count;
    // The earliest offset any criterion is met at, as in eval's trials: against a learned
    // opponent partner, its head and strikes as the environment tracks them through the
    // action from what the controller saw at the decision (the partner's root, graph state
    // and phase); a target the page drags stands still.
    std::uint32_t first = 0;
    const TrackedOpponent* tracked = world.partner(i) >= 0 ? opponent : nullptr;
    for (SuccessCriterion::Tracker& tracker : s.trackers[i])
      if (const std::uint32_t t = tracker.play(model, d.action, d.target, tracked); t > 0 && (first == 0 || t < first))
        first = t;
    if (first == 0) continue;
    ++s.successes;
    // The decision was made this frame: the success lands `first` frames on.
    s.successTimes.push_back(world.time() + static_cast<double>(first - 1) * model.frameTime);
    for (auto& tracker : s.trackers[i]) tracker = SuccessCriterion::Tracker(*tracker.criterion(), model.frameTime);
  }
}

// Why the page runs slower than it asked, in a sentence, or "": its world's steps or its
// messages spent more than its share of the server's thread.
std::string ViewerSession::slowed(const PageShare& share) const {
  const State& s = *state_;
  if (share.ticksSkipped == 0 && s.framesShed == 0 && share.messagesWaited == 0) return {};
  std::string text = fmt::format("The server shares its time among {} page{}, {:.0f} ms a second each;", share.pages,
                                 share.pages == 1 ? "" : "s", share.secondsPerSecond * 1e3);
  if (share.ticksSkipped > 0 || s.framesShed > 0)
    text += fmt::format(
        " this world asks for more ({} avatars, {}{} at speed {}), so {} of its last {} steps were skipped{} and it "
        "runs slower.",
        state_->world->avatarCount(), s.controller,
        s.controller == "online_search" ? fmt::format(" ({} actions ahead)", s.horizon) : std::string(), s.speed,
        share.ticksSkipped, share.ticks,
        s.framesShed == 0 ? std::string() : fmt::format(", {} frames were cut short", s.framesShed));
  if (share.messagesWaited > 0)
    text += fmt::format(
        " {}{} of this page's messages waited {:.1f} s in all for its share or for another page's costly message to "
        "end (a change of mode or crowd, a lesson's start cost the most); the page's world holds still and its "
        "further messages wait behind them.",
        share.ticksSkipped > 0 || s.framesShed > 0 ? "And " : "", share.messagesWaited, share.waitedSeconds);
  return text;
}

std::string ViewerSession::stats(std::size_t framesSent, std::size_t framesDropped, const PageShare& share) {
  State& s = *state_;
  const World& world = *s.world;
  const double window = std::min(30.0, std::max(world.time(), 1.0));
  const std::string why = slowed(share);
  json j = {
      {"type", "stats"},
      {"time", world.time()},
      {"frame", world.frame()},
      {"paused", s.paused},
      {"speed", s.speed},
      {"hits", world.landedCount()},
      {"blocked", world.blockedCount()},
      {"hits_per_minute", static_cast<double>(s.hitTimes.size()) / window * 60.0},
      {"successes", s.successes},
      {"successes_per_minute", static_cast<double>(s.successTimes.size()) / window * 60.0},
      {"decisions", world.decisions()},
      {"decision_us", s.decisions.count ? s.decisions.seconds / static_cast<double>(s.decisions.count) * 1e6 : 0.0},
      {"server_ms_per_frame", s.busyFrames ? s.busySeconds / static_cast<double>(s.busyFrames) * 1e3 : 0.0},
      {"frames_sent", framesSent},
      {"frames_dropped", framesDropped},
      {"bytes_per_avatar_frame", avatarRecordBytes(assets_->session->graph.db.skeleton->jointCount())},
      {"share_ms_per_s", round3(share.secondsPerSecond * 1e3)},
      {"steps_skipped", share.ticksSkipped},
      {"frames_shed", s.framesShed},
      {"messages_waited", share.messagesWaited},
      {"slowed", why.empty() ? json(nullptr) : json(why)}};
  s.decisions = {};
  s.framesShed = 0;
  s.busySeconds = 0;
  s.busyFrames = 0;
  return j.dump();
}

}  // namespace mgrl::serve
