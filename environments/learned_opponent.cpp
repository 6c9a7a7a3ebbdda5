// learned_opponent (Lee & Lee sec. 7's next step, "sparring with a real
// opponent"): the opponent is another avatar of the same graph that plays graph actions
// itself, chosen by a policy table (self-play: the same behaviour's previous round) with the
// runtime controller's greedy rule, or in round 0 by a scripted rule. Its state in the
// avatar frame is where it stands and which way it faces (TargetState::position, ::heading,
// as for `opponent`) and what it is doing: TargetState::opponent = s * phases + b, the graph
// state s its current action ends at and how far it is from there, in `phases` buckets b of
// that action's length (b = 0: about to arrive).
//
// Time (the two fighters' actions end at different moments). The avatar decides at its
// action boundaries, the opponent at its own. Across one avatar action of L frames:
//   1. the opponent plays what is left of its current action; at a decision only (s, b) is
//      known, so it plays the last tau frames of s's representative incoming action (the
//      median-length one), tau the middle of bucket b;
//   2. if it reaches s within the L frames (after tau of them), it decides there, seeing the
//      avatar where the avatar is at that frame (and, for a table with opponent layers, the
//      avatar's own (state, phase)), and plays the chosen action from its first frame;
//      this repeats, so it may decide several times during one long avatar action;
//   3. at the avatar's end its root is exact (it moved by the frames it played); its action
//      and frame are quantised to (end state, phase bucket): the sample-and-hold snap.
// Everything is a function of (action, state) alone: deterministic, so value iteration
// tabulates it, and track() gives the frames the rewards read (its actual strikes, its body).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>

#include <fmt/format.h>

#include "environments.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/learning/discretizer.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_table.hpp"
#include "mgrl/learning/signals.hpp"

namespace mgrl::environments {

namespace {

GroundMotion inverted(const GroundMotion& g) {
  const Eigen::Vector3d back = inverseTransformPoint(g, Eigen::Vector3d::Zero());
  return {back.x(), back.z(), -g.dyaw};
}

}  // namespace

std::uint64_t freshGeneration() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

void LearnedOpponent::bind(const StateActionModel& m) {
  policyGeneration_ = freshGeneration();
  const std::size_t states = m.stateCount();
  if (states == 0) throw Error("learned_opponent: the graph has no states");
  if (states * static_cast<std::size_t>(phases_) > kMaxGridVertices)
    throw Error(fmt::format("learned_opponent: expected at most {} opponent states, found {} states x {} phases",
                            kMaxGridVertices, states, phases_));
  // The representative incoming action of each state: the median length among the actions
  // that end there (ties: the lowest index), so a state's phases cut a typical action.
  std::vector<std::vector<std::uint32_t>> incoming(states);
  for (std::uint32_t a = 0; a < m.actionCount(); ++a) incoming[m.actionTo[a]].push_back(a);
  representative_.assign(states, 0);
  for (std::size_t s = 0; s < states; ++s) {
    std::vector<std::uint32_t>& in = incoming[s];
    if (in.empty())
      throw Error(
          fmt::format("learned_opponent: state {} has no incoming action, so no phase of the opponent can "
                      "end there (expected a strongly connected graph)",
                      s));
    std::stable_sort(in.begin(), in.end(),
                     [&](std::uint32_t x, std::uint32_t y) { return m.actionLength(x) < m.actionLength(y); });
    representative_[s] = in[(in.size() - 1) / 2];
  }
  cosYaw_.resize(m.actionCount());
  sinYaw_.resize(m.actionCount());
  for (std::size_t a = 0; a < m.actionCount(); ++a) {
    cosYaw_[a] = std::cos(m.actionDisplacement[3 * a + 2]);
    sinYaw_[a] = std::sin(m.actionDisplacement[3 * a + 2]);
  }
  BodyPoint head = parseBodyPoint("head");
  head_ = bindBodyPoint(m, head, nullptr) ? head.joint : -1;
  model_ = &m;
}

std::size_t LearnedOpponent::opponentStates() const {
  if (!model_) throw Error("learned_opponent: asked for its states before bind()");
  return model_->stateCount() * static_cast<std::size_t>(phases_);
}

std::uint32_t LearnedOpponent::phaseOf(std::uint32_t tau, std::uint32_t length) const {
  // tau in [1, length]: bucket b covers tau in (b length / P, (b + 1) length / P].
  return static_cast<std::uint32_t>(opponentStateIndex(0, tau, length, phases_));
}

std::uint32_t LearnedOpponent::framesLeft(const StateActionModel& m, std::uint32_t s, std::uint32_t b) const {
  const auto length = static_cast<std::uint32_t>(m.actionLength(representative_[s]));
  const double middle = (b + 0.5) * length / phases_ + 0.5;
  return std::clamp<std::uint32_t>(static_cast<std::uint32_t>(std::lround(middle)), 1, length);
}

void LearnedOpponent::playPolicy(const Discretizer* grid, std::shared_ptr<const QTable> table, const std::string& key) {
  if (!table) {
    grid_ = nullptr;
    table_.reset();
    key_.clear();
    policyGeneration_ = freshGeneration();
    return;
  }
  if (!grid) throw Error("learned_opponent: a policy table needs its grid");
  if (model_ && table->actionCount() != model_->actionCount())
    throw Error(fmt::format("learned_opponent: expected a table of {} actions (the graph's), found {}",
                            model_->actionCount(), table->actionCount()));
  if (table->vertexCount() != grid->vertexCount())
    throw Error(fmt::format("learned_opponent: expected a table over the grid's {} vertices, found {}",
                            grid->vertexCount(), table->vertexCount()));
  grid_ = grid;
  table_ = std::move(table);
  key_ = key;
  policyGeneration_ = freshGeneration();
}

std::uint32_t LearnedOpponent::choose(const StateActionModel& m, std::uint32_t s, const GroundMotion& self,
                                      std::size_t avatarAction, std::uint32_t t, double height) const {
  const std::uint32_t begin = m.stateActionBegin[s], n = m.stateActionBegin[s + 1] - begin;
  const GroundMotion avatar = actionFrameMotion(m, avatarAction, t);
  if (table_) {
    // The runtime controller's rule (PolicyController::choose): the greedy action of the
    // table interpolated at the avatar as the opponent sees it, clamped into the grid, ties
    // to the lowest index. The avatar's own state is its action's end and its phase.
    TargetState seen(inverseTransformPoint(self, Eigen::Vector3d(avatar.dx, height, avatar.dz)), 0.0,
                     std::remainder(avatar.dyaw - self.dyaw, 2 * M_PI));
    if (grid_->hasOpponentLayers()) {
      const auto length = static_cast<std::uint32_t>(m.actionLength(avatarAction));
      const std::uint32_t tau = std::max<std::uint32_t>(1, length - t);
      seen.opponent = static_cast<std::int32_t>(m.actionTo[avatarAction] * static_cast<std::uint32_t>(phases_) +
                                                phaseOf(tau, length));
    }
    return static_cast<std::uint32_t>(greedyAction(m, *grid_, *table_, s, seen));
  }
  // Round 0, scripted: the action that ends closest to stop_distance from the avatar and
  // facing it (0.3 m per radian off), less `strike_bonus` m if one of its effective punches
  // comes within `reach` of the avatar's head (the root's at head height without one).
  // The opponent's own rotation is applied by hand (one sine and cosine per decision, not
  // per candidate): this runs for every (action, vertex) pair a table is tabulated over.
  const Eigen::Vector3d head = head_ >= 0 ? jointAt(m, m.actionFrameBegin[avatarAction] + t - 1, head_)
                                          : Eigen::Vector3d(avatar.dx, 1.6, avatar.dz);
  const double c = std::cos(self.dyaw), sn = std::sin(self.dyaw);
  auto place = [&](double x, double z) {  // applyMotion(self, (x, ., z)) on the ground
    return std::pair<double, double>{self.dx + c * x + sn * z, self.dz - sn * x + c * z};
  };
  std::uint32_t best = 0;
  double bestScore = 0;
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint32_t o = begin + j;
    const double* d = &m.actionDisplacement[3 * o];
    const auto [ex, ez] = place(d[0], d[1]);
    const double dx = avatar.dx - ex, dz = avatar.dz - ez;
    const double gap = std::sqrt(dx * dx + dz * dz);
    // The avatar's direction in the end's frame: turn (dx, dz) back by the end's yaw.
    const double ce = c * cosYaw_[o] - sn * sinYaw_[o], se = sn * cosYaw_[o] + c * sinYaw_[o];
    const double off = gap > 0 ? std::abs(std::atan2(ce * dx - se * dz, se * dx + ce * dz)) : 0.0;
    double score = std::abs(gap - stopDistance_) + 0.3 * off;
    for (const ActionHit& h : m.hitsOf(o)) {
      const auto [hx, hz] = place(h.x, h.z);
      const double ux = hx - head.x(), uy = h.y - head.y(), uz = hz - head.z();
      if (ux * ux + uy * uy + uz * uz < reach_ * reach_) {
        score -= strikeBonus_;
        break;
      }
    }
    if (j == 0 || score < bestScore) {
      best = j;
      bestScore = score;
    }
  }
  return begin + best;
}

TargetState LearnedOpponent::simulate(const StateActionModel& m, std::size_t action, const TargetState& e,
                                      std::vector<OpponentFrame>* out) const {
  if (!model_) throw Error("learned_opponent: used before bind()");
  const auto phases = static_cast<std::uint32_t>(phases_);
  const std::size_t count = m.stateCount() * phases;
  if (e.opponent < 0 || static_cast<std::size_t>(e.opponent) >= count)
    throw Error(fmt::format("learned_opponent: expected an opponent state in [0, {}), found {}", count, e.opponent));
  const auto length = static_cast<std::uint32_t>(m.actionLength(action));
  std::uint32_t s = static_cast<std::uint32_t>(e.opponent) / phases;
  // 1. What is left of its current action: the representative's last tau frames.
  std::uint32_t current = representative_[s];
  auto currentLength = static_cast<std::uint32_t>(m.actionLength(current));
  std::uint32_t played = currentLength - framesLeft(m, s, static_cast<std::uint32_t>(e.opponent) % phases);
  const GroundMotion now{e.position.x(), e.position.z(), e.heading};
  GroundMotion decision = composeMotion(now, inverted(actionFrameMotion(m, current, played)));
  std::uint32_t t = 0;  // the avatar's frames played
  for (;;) {
    const std::uint32_t step = std::min(currentLength - played, length - t);
    if (out) {
      const double c = std::cos(decision.dyaw), sn = std::sin(decision.dyaw);
      for (std::uint32_t k = 1; k <= step; ++k) out->push_back({decision, current, played + k, c, sn});
    }
    t += step;
    played += step;
    if (played < currentLength) break;  // the avatar's action ends first
    // 2. It reaches its end state at the avatar's frame t and decides there.
    decision = composeMotion(decision, m.displacement(current));
    s = m.actionTo[current];
    current = choose(m, s, decision, action, t, e.position.y());
    currentLength = static_cast<std::uint32_t>(m.actionLength(current));
    played = 0;
    if (t == length) break;  // both decide at this frame
  }
  // 3. Its root at the avatar's end, seen from there; its action snapped to (end, phase).
  const GroundMotion root = composeMotion(decision, actionFrameMotion(m, current, played));
  const GroundMotion d = m.displacement(action);
  TargetState next(inverseTransformPoint(d, Eigen::Vector3d(root.dx, e.position.y(), root.dz)), 0.0,
                   std::remainder(root.dyaw - d.dyaw, 2 * M_PI));
  next.opponent =
      static_cast<std::int32_t>(m.actionTo[current] * phases + phaseOf(currentLength - played, currentLength));
  return next;
}

namespace {

// The last track() on this thread: a table's tabulation asks the reward (which tracks the
// opponent) and then next() for the same pair, so next() reuses what track() simulated.
struct LastTrack {
  std::uint64_t generation = 0;  ///< the model and policy it was simulated with (0: none yet)
  std::size_t action = 0;
  TargetState from, to;
};
thread_local LastTrack lastTrack;

// Bit for bit, on purpose (the cache must not take -0 for 0 or hide a NaN), so memcmp.
bool same(const TargetState& a, const TargetState& b) {
  // NOLINTNEXTLINE(bugprone-suspicious-memory-comparison)
  return std::memcmp(a.position.data(), b.position.data(), 3 * sizeof(double)) == 0 &&
         std::memcmp(&a.speed, &b.speed, sizeof(double)) == 0 &&      // NOLINT(bugprone-suspicious-memory-comparison)
         std::memcmp(&a.heading, &b.heading, sizeof(double)) == 0 &&  // NOLINT(bugprone-suspicious-memory-comparison)
         a.opponent == b.opponent;
}

}  // namespace

TargetState LearnedOpponent::next(const StateActionModel& m, std::size_t action, const TargetState& e) const {
  const LastTrack& last = lastTrack;
  if (last.generation == policyGeneration_ && last.action == action && same(last.from, e)) return last.to;
  return simulate(m, action, e, nullptr);
}

void LearnedOpponent::track(const StateActionModel& m, std::size_t action, const TargetState& e,
                            std::vector<OpponentFrame>& out) const {
  out.clear();
  const TargetState to = simulate(m, action, e, &out);
  lastTrack = {policyGeneration_, action, e, to};
}

TargetState LearnedOpponent::draw(const Eigen::Vector3d& position, Rng& rng) const {
  // A trial's opponent starts facing the avatar, in a graph state and phase drawn uniformly.
  TargetState e(position, 0.0, std::atan2(-position.x(), -position.z()));
  e.opponent = static_cast<std::int32_t>(rng.below(opponentStates()));
  return e;
}

void registerLearnedOpponent(EnvironmentRegistry& registry) {
  registry.add(
      {"learned_opponent",
       "the target is another avatar of the same graph playing graph actions: its ground position, facing and what "
       "it is doing (the state its action ends at and a phase: one grid layer each) are the state; it plays a policy "
       "table with the runtime's greedy rule (self-play rounds), or in round 0 a scripted pursuer that punches when "
       "in reach; the rewards see its actual body and strikes",
       {ParamSpec::choiceOrName("policy", "scripted", {"scripted"}, "a policy bundle directory",
                                "scripted: round 0's pursuer; else a bundle whose table for this behaviour (same "
                                "grid and opponent layers) the opponent plays"),
        ParamSpec::integer("phases", 2, 1, 16, "buckets",
                           "how finely the opponent's progress through its action is told apart (opponent states = "
                           "graph states x phases)"),
        ParamSpec::integer("rounds", 1, 1, 20, "rounds",
                           "mgrl train: self-play rounds; round 1 against `policy`, round k against round k - 1's "
                           "table (or the rounds' mean, `against`); every round is kept in the bundle"),
        ParamSpec::choice("against", "previous", {"previous", "average"},
                          "self-play: round k's opponent plays round k - 1's table (previous), or greedily on the "
                          "mean of rounds 1..k - 1's tables (average: a stand-in for fictitious self-play, so that "
                          "a round cannot win by beating only the last one)"),
        ParamSpec::number("stop_distance", 0.9, 0, 10, "m", "scripted: the ground distance it closes to"),
        ParamSpec::number("reach", 0.3, 0.01, 2, "m",
                          "scripted: a punch whose tip comes this close to the head counts"),
        ParamSpec::number("strike_bonus", 0.5, 0, 10, "m", "scripted: how much a punch in reach outweighs position")},
       [](const Params& p) {
         return std::make_unique<LearnedOpponent>(
             p.choice("policy"), static_cast<int>(p.integer("phases")), static_cast<int>(p.integer("rounds")),
             p.choice("against") == "average", p.number("stop_distance"), p.number("reach"), p.number("strike_bonus"));
       }});
}

}  // namespace mgrl::environments
