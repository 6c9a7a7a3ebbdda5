#include "mgrl/graph/state_action_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/roles.hpp"

namespace mgrl {
namespace {

[[noreturn]] void fail(std::string_view source, std::string_view field, std::string_view expected,
                       std::string_view found) {
  throw Error(fmt::format("{}: {}: expected {}, found {}", source, field, expected, found));
}

void requireSize(std::string_view source, std::string_view field, std::size_t size, std::size_t expected,
                 std::string_view why) {
  if (size != expected) fail(source, field, fmt::format("{} entries ({})", expected, why), fmt::format("{}", size));
}

// An offset array: starts at 0, never decreases, ends at `end` (the size of what it indexes).
void requireOffsets(std::string_view source, std::string_view field, const std::vector<std::uint32_t>& v,
                    std::size_t end, std::string_view endName) {
  if (v.front() != 0) fail(source, fmt::format("{}[0]", field), "0", fmt::format("{}", v.front()));
  for (std::size_t i = 1; i < v.size(); ++i)
    if (v[i] < v[i - 1])
      fail(source, fmt::format("{}[{}]", field, i), fmt::format("at least {}[{}] = {}", field, i - 1, v[i - 1]),
           fmt::format("{}", v[i]));
  if (v.back() != end)
    fail(source, fmt::format("{}[{}]", field, v.size() - 1), fmt::format("{} = {} (the end)", endName, end),
         fmt::format("{}", v.back()));
}

void requireBelow(std::string_view source, std::string_view field, const std::vector<std::uint32_t>& v,
                  std::size_t limit, std::string_view what, std::string_view limitName) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (v[i] >= limit)
      fail(source, fmt::format("{}[{}]", field, i), fmt::format("{} below {} {}", what, limitName, limit),
           fmt::format("{}", v[i]));
}

void requireAscending(std::string_view source, std::string_view field, const std::vector<std::uint32_t>& v) {
  for (std::size_t i = 1; i < v.size(); ++i)
    if (v[i] <= v[i - 1])
      fail(source, fmt::format("{}[{}]", field, i),
           fmt::format("above {}[{}] = {} (strictly ascending)", field, i - 1, v[i - 1]), fmt::format("{}", v[i]));
}

template <class T>
void requireFinite(std::string_view source, std::string_view field, const std::vector<T>& v) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) fail(source, fmt::format("{}[{}]", field, i), "a finite number", fmt::format("{}", v[i]));
}

// Frame time, centroid and top speeds.
void checkScalars(const StateActionModel& m, std::string_view source) {
  if (!(m.frameTime > 0) || !std::isfinite(m.frameTime))
    fail(source, "frameTime", "a finite number of seconds above 0", fmt::format("{}", m.frameTime));
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(m.centroid[i]))
      fail(source, fmt::format("centroid[{}]", i), "a finite number", fmt::format("{}", m.centroid[i]));
  if (!(m.maxHitSpeed_mps >= 0) || !std::isfinite(m.maxHitSpeed_mps))
    fail(source, "maxHitSpeed_mps", "a finite speed of at least 0", fmt::format("{}", m.maxHitSpeed_mps));
  if (!(m.maxKickSpeed_mps >= 0) || !std::isfinite(m.maxKickSpeed_mps))
    fail(source, "maxKickSpeed_mps", "a finite speed of at least 0", fmt::format("{}", m.maxKickSpeed_mps));
}

void checkSizes(const StateActionModel& m, std::string_view source) {
  // Sizes first, so the checks after them index safely.
  if (m.clipOffset.empty()) fail(source, "clipOffset", "at least one entry", "none");
  if (m.transitions.size() % 2 != 0)
    fail(source, "transitions", "an even number of entries (pairs i, j)", fmt::format("{}", m.transitions.size()));
  requireSize(source, "transitionDistance", m.transitionDistance.size(), m.transitions.size() / 2,
              "one per transition pair");
  const std::size_t states = m.stateCount();
  const std::size_t actions = m.actionCount();
  const std::size_t frames = m.actionFrames.size();
  requireSize(source, "actionTo", m.actionTo.size(), actions, "one per action, as actionFrom");
  requireSize(source, "actionFrameBegin", m.actionFrameBegin.size(), actions + 1, "actions + 1");
  requireSize(source, "actionDisplacement", m.actionDisplacement.size(), 3 * actions, "3 per action");
  requireSize(source, "actionHitBegin", m.actionHitBegin.size(), actions + 1, "actions + 1");
  // No kicks at all may also be said with no actionKickBegin (models made by hand).
  if (!(m.actionKickBegin.empty() && m.kicks.empty()))
    requireSize(source, "actionKickBegin", m.actionKickBegin.size(), actions + 1, "actions + 1");
  requireSize(source, "stateActionBegin", m.stateActionBegin.size(), states + 1, "states + 1");
  requireSize(source, "frameRoot", m.frameRoot.size(), 3 * frames, "3 per action frame");
  requireSize(source, "frameCentroid", m.frameCentroid.size(), 3 * frames, "3 per action frame");
  requireSize(source, "frameEntersTransition", m.frameEntersTransition.size(), frames, "one per action frame");

  requireOffsets(source, "clipOffset", m.clipOffset, m.framesTotal, "framesTotal");
  requireOffsets(source, "actionFrameBegin", m.actionFrameBegin, frames, "the size of actionFrames");
  requireOffsets(source, "stateActionBegin", m.stateActionBegin, actions, "the number of actions");
  requireOffsets(source, "actionHitBegin", m.actionHitBegin, m.hits.size(), "the number of hits");
  if (!m.actionKickBegin.empty())
    requireOffsets(source, "actionKickBegin", m.actionKickBegin, m.kicks.size(), "the number of kicks");
}

// Transitions, states and actions: in range, sorted, each action ending at its end state.
void checkGraph(const StateActionModel& m, std::string_view source) {
  const std::size_t states = m.stateCount();
  const std::size_t actions = m.actionCount();
  requireBelow(source, "componentFrames", m.componentFrames, m.framesTotal, "a frame", "framesTotal");
  requireAscending(source, "componentFrames", m.componentFrames);
  requireBelow(source, "transitions", m.transitions, m.framesTotal, "a frame", "framesTotal");
  for (std::size_t e = 1; 2 * e < m.transitions.size(); ++e) {
    const std::uint32_t i0 = m.transitions[2 * e - 2], j0 = m.transitions[2 * e - 1];
    const std::uint32_t i1 = m.transitions[2 * e], j1 = m.transitions[2 * e + 1];
    if (i1 < i0 || (i1 == i0 && j1 < j0))
      fail(source, fmt::format("transitions[{}]", 2 * e), fmt::format("pairs sorted, at least ({}, {})", i0, j0),
           fmt::format("({}, {})", i1, j1));
  }
  requireFinite(source, "transitionDistance", m.transitionDistance);
  requireBelow(source, "stateFrame", m.stateFrame, m.framesTotal, "a frame", "framesTotal");
  requireAscending(source, "stateFrame", m.stateFrame);

  requireBelow(source, "actionFrames", m.actionFrames, m.framesTotal, "a frame", "framesTotal");
  requireBelow(source, "actionFrom", m.actionFrom, states, "a state", "stateCount");
  requireBelow(source, "actionTo", m.actionTo, states, "a state", "stateCount");
  for (std::size_t a = 1; a < actions; ++a)
    if (m.actionFrom[a] < m.actionFrom[a - 1])
      fail(source, fmt::format("actionFrom[{}]", a),
           fmt::format("at least actionFrom[{}] = {} (actions sorted by state)", a - 1, m.actionFrom[a - 1]),
           fmt::format("{}", m.actionFrom[a]));
  for (std::size_t s = 0; s < states; ++s)
    for (std::size_t a = m.stateActionBegin[s]; a < m.stateActionBegin[s + 1]; ++a)
      if (m.actionFrom[a] != s)
        fail(source, fmt::format("actionFrom[{}]", a),
             fmt::format("state {} (stateActionBegin[{}] = {} to [{}] = {})", s, s, m.stateActionBegin[s], s + 1,
                         m.stateActionBegin[s + 1]),
             fmt::format("{}", m.actionFrom[a]));
  for (std::size_t a = 0; a < actions; ++a) {
    if (m.actionFrameBegin[a + 1] == m.actionFrameBegin[a])
      fail(source, fmt::format("actionFrameBegin[{}]", a + 1),
           fmt::format("above actionFrameBegin[{}] = {} (every action has a frame)", a, m.actionFrameBegin[a]),
           fmt::format("{}", m.actionFrameBegin[a + 1]));
    // An action ends where its end state is, so the next decision starts from that frame.
    const std::size_t last = m.actionFrameBegin[a + 1] - 1;
    const std::uint32_t endFrame = m.stateFrame[m.actionTo[a]];
    if (m.actionFrames[last] != endFrame)
      fail(source, fmt::format("actionFrames[{}]", last),
           fmt::format("frame {} of state {} (action {} ends there)", endFrame, m.actionTo[a], a),
           fmt::format("{}", m.actionFrames[last]));
  }
  requireFinite(source, "actionDisplacement", m.actionDisplacement);
  requireFinite(source, "frameRoot", m.frameRoot);
  requireFinite(source, "frameCentroid", m.frameCentroid);
}

void checkJoints(const StateActionModel& m, std::string_view source) {
  const std::size_t frames = m.actionFrames.size();
  // The skeleton's joints: none at all, or every array sized by them.
  const std::size_t joints = m.jointNames.size();
  requireSize(source, "sourceJoint", m.sourceJoint.size(), 3 * std::size_t{m.framesTotal} * joints,
              "3 per source frame and joint");
  requireSize(source, "sourceJointSpeed", m.sourceJointSpeed.size(), std::size_t{m.framesTotal} * joints,
              "one per source frame and joint");
  if (joints > 0 || !m.roleJoint.empty())
    requireSize(source, "roleJoint", m.roleJoint.size(), roleNames().size(), "one per role");
  for (std::size_t r = 0; r < m.roleJoint.size(); ++r)
    if (m.roleJoint[r] < -1 || m.roleJoint[r] >= static_cast<std::int64_t>(joints))
      fail(source, fmt::format("roleJoint[{}]", r), fmt::format("a joint in [-1, {})", joints),
           fmt::format("{}", m.roleJoint[r]));
  requireFinite(source, "sourceJoint", m.sourceJoint);
  for (std::size_t i = 0; i < m.sourceJointSpeed.size(); ++i)
    if (!(m.sourceJointSpeed[i] >= 0) || !std::isfinite(m.sourceJointSpeed[i]))
      fail(source, fmt::format("sourceJointSpeed[{}]", i), "a finite speed of at least 0",
           fmt::format("{}", m.sourceJointSpeed[i]));
  for (std::size_t i = 0; i < frames; ++i)
    if (m.frameEntersTransition[i] > 1)
      fail(source, fmt::format("frameEntersTransition[{}]", i), "0 or 1",
           fmt::format("{}", m.frameEntersTransition[i]));
}

// Strikes (punches or kicks): each belongs to its action, sorted by (offset, side) there.
void checkStrikes(const StateActionModel& m, std::string_view source, std::string_view name,
                  const std::vector<ActionHit>& list, const std::vector<std::uint32_t>& begin,
                  std::string_view beginName) {
  const std::size_t actions = m.actionCount();
  for (std::size_t a = 0; a < actions; ++a) {
    for (std::size_t h = begin[a]; h < begin[a + 1]; ++h) {
      const ActionHit& hit = list[h];
      if (hit.action != a)
        fail(source, fmt::format("{}[{}].action", name, h), fmt::format("{} ({})", a, beginName),
             fmt::format("{}", hit.action));
      if (hit.offset < 1 || hit.offset > m.actionLength(a))
        fail(source, fmt::format("{}[{}].offset", name, h),
             fmt::format("an offset in [1, {}] (the length of action {})", m.actionLength(a), a),
             fmt::format("{}", hit.offset));
      if (hit.hand > 1)
        fail(source, fmt::format("{}[{}].hand", name, h), "0 (left) or 1 (right)", fmt::format("{}", hit.hand));
      if (h > begin[a]) {
        const ActionHit& previous = list[h - 1];
        if (hit.offset < previous.offset || (hit.offset == previous.offset && hit.hand < previous.hand))
          fail(source, fmt::format("{}[{}]", name, h),
               fmt::format("sorted by (offset, side), at least ({}, {})", previous.offset, previous.hand),
               fmt::format("({}, {})", hit.offset, hit.hand));
      }
      const float values[3] = {hit.x, hit.y, hit.z};
      for (int k = 0; k < 3; ++k)
        if (!std::isfinite(values[k]))
          fail(source, fmt::format("{}[{}].{}", name, h, "xyz"[k]), "a finite number", fmt::format("{}", values[k]));
      if (!(hit.weight > 0 && hit.weight <= 1))
        fail(source, fmt::format("{}[{}].weight", name, h), "a weight in (0, 1]", fmt::format("{}", hit.weight));
    }
  }
}

}  // namespace

ActionFrameStats actionFrameStats(const StateActionModel& m) {
  ActionFrameStats s;
  if (m.actionCount() == 0) return s;
  s.min = SIZE_MAX;
  double sum = 0;
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    const std::size_t l = m.actionLength(a);
    s.min = std::min(s.min, l);
    s.max = std::max(s.max, l);
    sum += static_cast<double>(l);
  }
  s.mean = sum / static_cast<double>(m.actionCount());
  return s;
}

std::vector<std::size_t> componentFramesByClip(const StateActionModel& m, std::size_t clips) {
  if (clips + 1 != m.clipOffset.size()) return {};
  std::vector<std::size_t> inside(clips, 0);
  std::size_t c = 0;
  for (const std::uint32_t f : m.componentFrames) {  // ascending
    while (f >= m.clipOffset[c + 1]) ++c;
    ++inside[c];
  }
  return inside;
}

void checkModel(const StateActionModel& m, std::string_view source) {
  checkScalars(m, source);
  checkSizes(m, source);  // first, so the checks after them index safely
  checkGraph(m, source);
  checkJoints(m, source);
  checkStrikes(m, source, "hits", m.hits, m.actionHitBegin, "actionHitBegin");
  if (!m.actionKickBegin.empty()) checkStrikes(m, source, "kicks", m.kicks, m.actionKickBegin, "actionKickBegin");
}

}  // namespace mgrl
