#include "mgrl/graph/motion_graph.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include "mgrl/motion/kinematics.hpp"

namespace mgrl {

const AvatarFrame& avatarFrameAt(const MotionDatabase& db, std::uint32_t frame) {
  const std::size_t c = db.clipOf(frame);
  return db.clips[c].annotation.frames[frame - db.offsets[c]];
}

namespace {

// The skeleton's joints at every source frame (StateActionModel::sourceJoint): positions in
// the frame's own avatar frame, speeds in the capture.
void addSourceJoints(const MotionDatabase& db, StateActionModel& m) {
  const Skeleton& skeleton = *db.skeleton;
  const std::size_t joints = skeleton.jointCount();
  for (const Joint& joint : skeleton.joints()) m.jointNames.push_back(joint.name);
  for (int j : roleJointIndices(db.roles)) m.roleJoint.push_back(j);
  m.sourceJoint.reserve(3 * std::size_t{m.framesTotal} * joints);
  m.sourceJointSpeed.reserve(std::size_t{m.framesTotal} * joints);
  for (const Clip& clip : db.clips) {
    const std::vector<Eigen::Vector3d> positions = jointPositions(clip.motion);
    const std::vector<Eigen::Vector3d> speeds = velocities(positions, joints, clip.motion.frameTime());
    for (std::size_t f = 0; f < clip.motion.frameCount(); ++f) {
      const AvatarFrame& frame = clip.annotation.frames[f];
      for (std::size_t j = 0; j < joints; ++j) {
        const Eigen::Vector3d p = frame.toAvatar(positions[f * joints + j]);
        m.sourceJoint.insert(m.sourceJoint.end(),
                             {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
        m.sourceJointSpeed.push_back(static_cast<float>(speeds[f * joints + j].norm()));
      }
    }
  }
}

}  // namespace

GroundMotion relativeMotion(const AvatarFrame& from, const AvatarFrame& to) {
  const Eigen::Vector3d d = from.toAvatar(to.origin);
  return {d.x(), d.z(), std::remainder(to.yaw - from.yaw, 2 * M_PI)};
}

Eigen::Vector3d transformPoint(const GroundMotion& motion, const Eigen::Vector3d& point) {
  // Avatar-frame axes: +Z facing, +X left; turning by yaw maps +Z to (sin yaw, cos yaw).
  const double c = std::cos(motion.dyaw), s = std::sin(motion.dyaw);
  return {motion.dx + c * point.x() + s * point.z(), point.y(), motion.dz - s * point.x() + c * point.z()};
}

GroundMotion compose(const GroundMotion& a, const GroundMotion& b) {
  const Eigen::Vector3d end = transformPoint(a, {b.dx, 0, b.dz});
  return {end.x(), end.z(), std::remainder(a.dyaw + b.dyaw, 2 * M_PI)};
}

namespace {

// Frame graph in compressed rows: out-edges of frame f are target[begin[f], begin[f + 1]).
struct FrameGraph {
  std::vector<std::uint32_t> begin;
  std::vector<std::uint32_t> target;
};

FrameGraph frameGraph(const MotionDatabase& db, const std::vector<TransitionCandidate>& transitions) {
  const std::uint32_t n = db.frameCount();
  FrameGraph g;
  g.begin.assign(n + 1, 0);
  std::vector<std::uint8_t> natural(n, 0);
  for (std::size_t c = 0; c < db.clips.size(); ++c)
    for (std::uint32_t f = db.offsets[c]; f + 1 < db.offsets[c + 1]; ++f) natural[f] = 1;
  for (std::uint32_t f = 0; f < n; ++f) g.begin[f + 1] = natural[f];
  for (const auto& t : transitions) ++g.begin[t.from + 1];
  for (std::uint32_t f = 0; f < n; ++f) g.begin[f + 1] += g.begin[f];
  g.target.resize(g.begin[n]);
  std::vector<std::uint32_t> fill(g.begin.begin(), g.begin.end() - 1);
  for (std::uint32_t f = 0; f < n; ++f)
    if (natural[f]) g.target[fill[f]++] = f + 1;
  for (const auto& t : transitions) g.target[fill[t.from]++] = t.to;
  for (std::uint32_t f = 0; f < n; ++f) std::sort(g.target.begin() + g.begin[f], g.target.begin() + g.begin[f + 1]);
  return g;
}

// Tarjan's strongly connected components without recursion (graphs of 10^5 frames would
// overflow the stack). Returns the component of every vertex.
std::vector<std::uint32_t> stronglyConnected(const FrameGraph& g, std::size_t* count) {
  const std::uint32_t n = static_cast<std::uint32_t>(g.begin.size() - 1);
  constexpr std::uint32_t kUnset = UINT32_MAX;
  std::vector<std::uint32_t> index(n, kUnset), low(n, 0), component(n, kUnset), stack;
  std::vector<std::uint8_t> onStack(n, 0);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> call;  // (vertex, next edge)
  std::uint32_t counter = 0, components = 0;
  for (std::uint32_t root = 0; root < n; ++root) {
    if (index[root] != kUnset) continue;
    call.push_back({root, g.begin[root]});
    index[root] = low[root] = counter++;
    stack.push_back(root);
    onStack[root] = 1;
    while (!call.empty()) {
      auto& [v, edge] = call.back();
      if (edge < g.begin[v + 1]) {
        const std::uint32_t w = g.target[edge++];
        if (index[w] == kUnset) {
          index[w] = low[w] = counter++;
          stack.push_back(w);
          onStack[w] = 1;
          call.push_back({w, g.begin[w]});
        } else if (onStack[w]) {
          low[v] = std::min(low[v], index[w]);
        }
        continue;
      }
      const std::uint32_t done = v;
      call.pop_back();
      if (!call.empty()) low[call.back().first] = std::min(low[call.back().first], low[done]);
      if (low[done] == index[done]) {
        std::uint32_t w;
        do {
          w = stack.back();
          stack.pop_back();
          onStack[w] = 0;
          component[w] = components;
        } while (w != done);
        ++components;
      }
    }
  }
  *count = components;
  return component;
}

// The strikes of one kind (Annotation::hits or ::kicks) by global frame: begin[f] to
// begin[f + 1] index `list`. Raises `fastest` to their top speed and, if asked, leaves
// their mean tip (avatar frame) in *centroidSum.
struct StrikeIndex {
  std::vector<std::uint32_t> begin;  // per global frame
  std::vector<const EffectiveHit*> list;
};

StrikeIndex indexStrikes(const MotionDatabase& db, std::vector<EffectiveHit> Annotation::*member, double& fastest,
                         Eigen::Vector3d* centroidSum) {
  const std::uint32_t n = db.frameCount();
  StrikeIndex index;
  index.begin.assign(n + 1, 0);
  std::size_t count = 0;
  for (std::size_t c = 0; c < db.clips.size(); ++c)
    for (const EffectiveHit& h : db.clips[c].annotation.*member) {
      ++index.begin[db.offsets[c] + h.frame + 1];
      if (centroidSum) *centroidSum += h.tipAvatar;
      ++count;
      fastest = std::max(fastest, h.speed_mps);
    }
  if (centroidSum && count) *centroidSum /= static_cast<double>(count);
  for (std::uint32_t f = 0; f < n; ++f) index.begin[f + 1] += index.begin[f];
  index.list.resize(index.begin[n]);
  std::vector<std::uint32_t> fill(index.begin.begin(), index.begin.end() - 1);
  for (std::size_t c = 0; c < db.clips.size(); ++c)
    for (const EffectiveHit& h : db.clips[c].annotation.*member) index.list[fill[db.offsets[c] + h.frame]++] = &h;
  return index;
}

// The strikes at frame v, carried into the decision's avatar frame by `root`.
void addStrikes(const StrikeIndex& index, std::uint32_t v, const GroundMotion& root, std::uint32_t a,
                std::uint32_t offset, double fastest, std::vector<ActionHit>& into) {
  for (std::uint32_t h = index.begin[v]; h < index.begin[v + 1]; ++h) {
    const EffectiveHit& hit = *index.list[h];
    const Eigen::Vector3d p = transformPoint(root, hit.tipAvatar);
    into.push_back({a, offset, static_cast<std::uint8_t>(hit.hand), static_cast<float>(p.x()),
                    static_cast<float>(p.y()), static_cast<float>(p.z()), static_cast<float>(hit.speed_mps / fastest)});
  }
}

// The largest strongly connected component (on a tie, the one holding the earliest frame,
// so the choice is stable): a flag per frame, and its size.
std::size_t largestComponent(const FrameGraph& graph, std::vector<std::uint8_t>& inside,
                             std::size_t* components = nullptr) {
  const auto n = static_cast<std::uint32_t>(graph.begin.size() - 1);
  std::size_t count = 0;
  const std::vector<std::uint32_t> component = stronglyConnected(graph, &count);
  std::vector<std::uint32_t> size(count, 0);
  for (std::uint32_t c : component) ++size[c];
  std::uint32_t best = component[0];
  for (std::uint32_t f = 0; f < n; ++f)
    if (size[component[f]] > size[best]) best = component[f];
  inside.assign(n, 0);
  for (std::uint32_t f = 0; f < n; ++f) inside[f] = component[f] == best ? 1 : 0;
  if (components) *components = count;
  return size[best];
}

// GraphParams::maxOutDegree: every frame keeps, of its transitions inside the largest
// component, the `degree` (less its natural successor) of smallest distance. A frame the
// pruned graph would lose from the component gets its dropped transitions back, smallest
// distance first, one per frame and round, until the component is whole again (every
// frame a dropped transition touches, in either direction, counts as touched).
std::vector<TransitionCandidate> boundOutDegree(const MotionDatabase& db, const std::vector<TransitionCandidate>& all,
                                                int degree, GraphBuildReport& report) {
  const std::uint32_t n = db.frameCount();
  std::vector<std::uint8_t> inside;
  const std::size_t whole = largestComponent(frameGraph(db, all), inside);
  std::vector<std::uint8_t> natural(n, 0);
  for (std::size_t c = 0; c < db.clips.size(); ++c)
    for (std::uint32_t f = db.offsets[c]; f + 1 < db.offsets[c + 1]; ++f) natural[f] = inside[f + 1];

  // The candidates inside, grouped by frame (`all` is sorted by frame), each group by
  // distance then target: the first `budget` of a group are kept.
  std::vector<TransitionCandidate> candidates;
  for (const TransitionCandidate& t : all)
    if (inside[t.from] && inside[t.to]) candidates.push_back(t);
  std::vector<std::uint8_t> kept(candidates.size(), 0);
  std::vector<std::size_t> groupBegin;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (i == 0 || candidates[i].from != candidates[i - 1].from) groupBegin.push_back(i);
  groupBegin.push_back(candidates.size());
  for (std::size_t g = 0; g + 1 < groupBegin.size(); ++g) {
    const auto first = candidates.begin() + static_cast<std::ptrdiff_t>(groupBegin[g]);
    const auto last = candidates.begin() + static_cast<std::ptrdiff_t>(groupBegin[g + 1]);
    std::sort(first, last, [](const TransitionCandidate& a, const TransitionCandidate& b) {
      return a.distance != b.distance ? a.distance < b.distance : a.to < b.to;
    });
    const std::size_t budget = static_cast<std::size_t>(degree) - natural[first->from];
    for (std::size_t i = groupBegin[g]; i < std::min(groupBegin[g + 1], groupBegin[g] + budget); ++i) kept[i] = 1;
  }
  auto keptList = [&] {
    std::vector<TransitionCandidate> list;
    for (std::size_t i = 0; i < candidates.size(); ++i)
      if (kept[i]) list.push_back(candidates[i]);
    std::sort(list.begin(), list.end(), [](const TransitionCandidate& a, const TransitionCandidate& b) {
      return a.from != b.from ? a.from < b.from : a.to < b.to;
    });
    return list;
  };
  std::vector<TransitionCandidate> result = keptList();
  std::vector<std::uint8_t> now;
  while (largestComponent(frameGraph(db, result), now) < whole) {
    ++report.repairRounds;
    std::size_t restored = 0;
    for (std::size_t g = 0; g + 1 < groupBegin.size(); ++g)
      for (std::size_t i = groupBegin[g]; i < groupBegin[g + 1]; ++i)
        if (!kept[i] && (!now[candidates[i].from] || !now[candidates[i].to])) {
          kept[i] = 1;
          ++restored;
          break;
        }
    report.transitionsRestored += restored;
    result = keptList();
    if (restored == 0) break;  // cannot happen: with every transition back the component is whole
  }
  report.outDegreeBound = degree;
  report.transitionsPruned = candidates.size() - result.size();
  return result;
}

}  // namespace

StateActionModel buildStateActionModel(const MotionDatabase& db, const GraphParams& params, GraphBuildReport* report) {
  params.validate();
  GraphBuildReport local;
  const FrameFeatures features = computeFrameFeatures(db, params);
  std::vector<TransitionCandidate> transitions = findTransitions(db, features, params, &local.search);
  local.transitionsFound = transitions.size();
  if (const int degree = params.outDegreeFor(db.frameCount() * db.frameTime); degree > 0)
    transitions = boundOutDegree(db, transitions, degree, local);

  const std::uint32_t n = db.frameCount();
  const FrameGraph graph = frameGraph(db, transitions);
  std::vector<std::uint8_t> inside;
  largestComponent(graph, inside, &local.components);

  StateActionModel m;
  m.frameTime = db.frameTime;
  m.framesTotal = n;
  m.clipOffset = db.offsets;
  for (std::uint32_t f = 0; f < n; ++f)
    if (inside[f]) m.componentFrames.push_back(f);
  for (std::size_t t = 0; t < transitions.size(); ++t) {
    const auto& c = transitions[t];
    if (inside[c.from] && inside[c.to]) {
      m.transitions.push_back(c.from);
      m.transitions.push_back(c.to);
      m.transitionDistance.push_back(c.distance);
    }
  }
  // Out-edges inside the component decide which frames are states.
  auto outInside = [&](std::uint32_t f, std::vector<std::uint32_t>& out) {
    out.clear();
    for (std::uint32_t e = graph.begin[f]; e < graph.begin[f + 1]; ++e)
      if (inside[graph.target[e]]) out.push_back(graph.target[e]);
  };
  std::vector<std::uint32_t> out;
  std::vector<std::uint32_t> stateOf(n, UINT32_MAX);
  for (std::uint32_t f : m.componentFrames) {
    outInside(f, out);
    if (out.size() >= 2) {
      stateOf[f] = static_cast<std::uint32_t>(m.stateFrame.size());
      m.stateFrame.push_back(f);
    }
  }
  if (m.stateFrame.size() < static_cast<std::size_t>(params.minStates)) {
    // Advise only the looser contact events than the one in use.
    const char* looser = params.contactEvent == ContactEvent::LeftFootLiftoff    ? "any_contact_change or none"
                         : params.contactEvent == ContactEvent::AnyContactChange ? "none"
                                                                                 : nullptr;
    throw Error(fmt::format(
        "graph: the largest strongly connected component keeps {} of {} frames ({:.0f} %) with {} states, expected at "
        "least graph.min_states = {}; {} transitions passed the tests ({} frames at a '{}' contact event): raise "
        "graph.threshold (now {}), {}add motion files",
        m.componentFrames.size(), n, 100.0 * static_cast<double>(m.componentFrames.size()) / std::max(n, 1u),
        m.stateFrame.size(), params.minStates, transitions.size(), local.search.eventFrames,
        contactEventName(params.contactEvent), params.threshold,
        looser ? fmt::format("use graph.contact_event: {}, or ", looser) : std::string("or ")));
  }

  // Effective hitting points of the data: their centroid (the paper's p(t) follows it) and
  // the fastest one (the hit reward's w(t) is normalised by it). Kicks the same way, apart:
  // they leave the centroid and the paper's hit reward as they were.
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const StrikeIndex punches = indexStrikes(db, &Annotation::hits, m.maxHitSpeed_mps, &sum);
  for (int i = 0; i < 3; ++i) m.centroid[i] = sum[i];
  const StrikeIndex kicks = indexStrikes(db, &Annotation::kicks, m.maxKickSpeed_mps, nullptr);
  // Collapse: every out-edge of a state starts an action that runs until the next state.
  m.stateActionBegin.push_back(0);
  m.actionFrameBegin.push_back(0);
  m.actionHitBegin.push_back(0);
  m.actionKickBegin.push_back(0);
  const Eigen::Vector3d centroid(m.centroid[0], m.centroid[1], m.centroid[2]);
  for (std::uint32_t s = 0; s < m.stateFrame.size(); ++s) {
    const std::uint32_t from = m.stateFrame[s];
    std::vector<std::uint32_t> starts;
    outInside(from, starts);
    for (std::uint32_t first : starts) {
      const auto a = static_cast<std::uint32_t>(m.actionFrom.size());
      GroundMotion root;  // avatar frame of the current frame, in the decision's
      std::uint32_t previous = from, v = first, offset = 0;
      for (;;) {
        ++offset;
        // Edge previous -> v: v continues its own clip from v - 1, which resembles
        // `previous` (the same frame unless the edge is a transition).
        root = compose(root, relativeMotion(avatarFrameAt(db, v - 1), avatarFrameAt(db, v)));
        m.actionFrames.push_back(v);
        m.frameRoot.insert(m.frameRoot.end(), {root.dx, root.dz, root.dyaw});
        const Eigen::Vector3d pc = transformPoint(root, centroid);
        m.frameCentroid.insert(m.frameCentroid.end(),
                               {static_cast<float>(pc.x()), static_cast<float>(pc.y()), static_cast<float>(pc.z())});
        m.frameEntersTransition.push_back(v != previous + 1 ? 1 : 0);
        addStrikes(punches, v, root, a, offset, m.maxHitSpeed_mps, m.hits);
        addStrikes(kicks, v, root, a, offset, m.maxKickSpeed_mps, m.kicks);
        if (stateOf[v] != UINT32_MAX) break;
        outInside(v, out);  // exactly one edge: v is not a state
        previous = v;
        v = out.front();
      }
      m.actionFrom.push_back(s);
      m.actionTo.push_back(stateOf[v]);
      m.actionFrameBegin.push_back(static_cast<std::uint32_t>(m.actionFrames.size()));
      m.actionDisplacement.insert(m.actionDisplacement.end(), {root.dx, root.dz, root.dyaw});
      m.actionHitBegin.push_back(static_cast<std::uint32_t>(m.hits.size()));
      m.actionKickBegin.push_back(static_cast<std::uint32_t>(m.kicks.size()));
    }
    m.stateActionBegin.push_back(static_cast<std::uint32_t>(m.actionFrom.size()));
  }
  addSourceJoints(db, m);
  if (report) *report = local;
  return m;
}

std::string librarySentence(const GraphBuildReport& report) {
  if (report.outDegreeBound == 0 && report.search.standingCutFrames == 0) return {};
  const std::string bound =
      report.outDegreeBound > 0
          ? fmt::format(
                "at most {} actions a state: {} transitions left out, {} of them put back to keep the "
                "component whole",
                report.outDegreeBound, report.transitionsPruned + report.transitionsRestored,
                report.transitionsRestored)
          : std::string("no bound on actions a state");
  return fmt::format("{}; {} cut points where the performer stands still", bound, report.search.standingCutFrames);
}

}  // namespace mgrl
