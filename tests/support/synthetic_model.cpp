#include "synthetic_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string_view>
#include <tuple>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/core/random.hpp"

namespace mgrl {
namespace {

[[noreturn]] void fail(std::string_view field, std::string_view expected, std::string_view found) {
  throw Error(fmt::format("synthetic model: {}: expected {}, found {}", field, expected, found));
}

void requireFinite(std::string_view field, double v) {
  if (!std::isfinite(v)) fail(field, "a finite number", fmt::format("{}", v));
}

void requireAtLeast(std::string_view field, double v, double low) {
  requireFinite(field, v);
  if (v < low) fail(field, fmt::format("at least {}", low), fmt::format("{}", v));
}

void requireIn(std::string_view field, double v, double low, double high) {
  requireFinite(field, v);
  if (v < low || v > high) fail(field, fmt::format("a value in [{}, {}]", low, high), fmt::format("{}", v));
}

void requireDistribution(std::string_view field, const BoundedNormal& d, double low, double high) {
  for (auto [name, v] : {std::pair{"mean", d.mean}, {"sd", d.sd}, {"min", d.min}, {"max", d.max}})
    requireFinite(fmt::format("{}.{}", field, name), v);
  requireAtLeast(fmt::format("{}.sd", field), d.sd, 0);
  requireIn(fmt::format("{}.min", field), d.min, low, high);
  requireIn(fmt::format("{}.max", field), d.max, d.min, high);
  if (d.mean < d.min || d.mean > d.max)
    fail(fmt::format("{}.mean", field), fmt::format("a value in [min, max] = [{}, {}]", d.min, d.max),
         fmt::format("{}", d.mean));
}

constexpr double kInf = std::numeric_limits<double>::infinity();

// Normal and gamma draws on top of mgrl::Rng, so a seed means the same numbers everywhere.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed) {}

  double uniform() { return rng_.uniform(); }
  std::uint64_t below(std::uint64_t n) { return rng_.below(n); }

  double normal() {
    if (haveSpare_) {
      haveSpare_ = false;
      return spare_;
    }
    // Box-Muller; 1 - u keeps the logarithm finite.
    const double r = std::sqrt(-2 * std::log(1 - rng_.uniform()));
    const double phi = 2 * M_PI * rng_.uniform();
    spare_ = r * std::sin(phi);
    haveSpare_ = true;
    return r * std::cos(phi);
  }

  // Inside [min + low, max - high], so that shifts of -low .. +high stay inside [min, max];
  // redrawn a bounded number of times, then clamped (only a degenerate spec gets there).
  double bounded(const BoundedNormal& d, double low = 0, double high = 0) {
    const double lo = d.min + low, hi = d.max - high;
    if (!(hi >= lo)) return 0.5 * (d.min + d.max);
    for (int attempt = 0; attempt < 64; ++attempt) {
      const double v = d.mean + d.sd * normal();
      if (v >= lo && v <= hi) return v;
    }
    return std::clamp(d.mean, lo, hi);
  }

  // Gamma with mean 1 and coefficient of variation cv (Marsaglia and Tsang 2000).
  double gammaMeanOne(double cv) {
    if (cv <= 0) return 1;
    const double shape = 1 / (cv * cv);
    const double boost = shape < 1 ? std::pow(uniform(), 1 / shape) : 1;  // gamma(k) = gamma(k + 1) U^(1/k)
    const double d = (shape < 1 ? shape + 1 : shape) - 1.0 / 3, c = 1 / std::sqrt(9 * d);
    for (;;) {
      const double x = normal();
      double v = 1 + c * x;
      if (v <= 0) continue;
      v = v * v * v;
      const double u = uniform();
      if (std::log(u) < 0.5 * x * x + d - d * v + d * std::log(v)) return d * v * boost / shape;
    }
  }

 private:
  Rng rng_;
  double spare_ = 0;
  bool haveSpare_ = false;
};

// Splits `total` into parts proportional to `weights` (largest remainders, ties to the
// lower index), so the parts sum to `total` exactly.
std::vector<std::uint32_t> apportion(std::size_t total, const std::vector<double>& weights) {
  const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  std::vector<std::uint32_t> part(weights.size());
  std::vector<double> rest(weights.size());
  std::size_t given = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    const double share = static_cast<double>(total) * weights[i] / sum;
    part[i] = static_cast<std::uint32_t>(std::floor(share));
    rest[i] = share - part[i];
    given += part[i];
  }
  std::vector<std::size_t> order(weights.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return rest[a] != rest[b] ? rest[a] > rest[b] : a < b;
  });
  for (std::size_t k = 0; given < total; ++k, ++given) ++part[order[k % order.size()]];
  return part;
}

// A damped oscillator driven by white noise, sampled every dt: the AR(2) process
// x_k = a1 x_(k-1) + a2 x_(k-2) + e_k whose poles are exp((-zeta w +- i w sqrt(1 - zeta^2)) dt),
// scaled to the stationary standard deviation `sd`. Each run starts from the stationary
// distribution, i.e. somewhere in the sway cycle, as a decision does.
class Sway {
 public:
  Sway(double sd, double period, double damping, double dt) {
    const double w = 2 * M_PI / period;
    const double r = std::exp(-damping * w * dt);
    a1_ = 2 * r * std::cos(w * std::sqrt(1 - damping * damping) * dt);
    a2_ = -r * r;
    // Stationary variance of AR(2): var(e) (1 - a2) / ((1 + a2) ((1 - a2)^2 - a1^2)).
    const double gain = (1 - a2_) / ((1 + a2_) * ((1 - a2_) * (1 - a2_) - a1_ * a1_));
    noise_ = sd / std::sqrt(gain);
    rho_ = a1_ / (1 - a2_);  // lag-1 autocorrelation
    sd_ = sd;
  }

  // Fills out[k] = x_(k+1) - x_0 for k < n.
  void run(Draw& draw, std::size_t n, double* out, std::size_t stride) const {
    const double x0 = sd_ * draw.normal();
    double previous = rho_ * x0 + sd_ * std::sqrt(1 - rho_ * rho_) * draw.normal(), current = x0;
    for (std::size_t k = 0; k < n; ++k) {
      const double next = a1_ * current + a2_ * previous + noise_ * draw.normal();
      previous = current;
      current = next;
      out[k * stride] = current - x0;
    }
  }

 private:
  double a1_ = 0, a2_ = 0, noise_ = 0, rho_ = 0, sd_ = 0;
};

struct Transition {
  std::uint32_t from, to;
  bool operator<(const Transition& o) const { return std::tie(from, to) < std::tie(o.from, o.to); }
  bool operator==(const Transition& o) const { return from == o.from && to == o.to; }
};

}  // namespace

void SyntheticModelSpec::validate() const {
  if (states < 1) fail("states", "at least 1", fmt::format("{}", states));
  if (actions < states)
    fail("actions", fmt::format("at least states = {} (every state needs an out-action)", states),
         fmt::format("{}", actions));
  if (actions > std::numeric_limits<std::uint32_t>::max())
    fail("actions", "at most 2^32 - 1", fmt::format("{}", actions));
  if (minFrames < 1) fail("minFrames", "at least 1", fmt::format("{}", minFrames));
  if (maxFrames < minFrames)
    fail("maxFrames", fmt::format("at least minFrames = {}", minFrames), fmt::format("{}", maxFrames));
  requireFinite("fps", fps);
  if (!(fps > 0)) fail("fps", "a frame rate above 0", fmt::format("{}", fps));
  requireAtLeast("outDegreeCv", outDegreeCv, 0);
  requireAtLeast("inDegreeCv", inDegreeCv, 0);
  requireDistribution("transitionDistance", transitionDistance, 0, kInf);
  requireDistribution("driftForward_mps", driftForward_mps, -kInf, kInf);
  requireDistribution("driftSideways_mps", driftSideways_mps, -kInf, kInf);
  requireDistribution("driftTurn_radps", driftTurn_radps, -kInf, kInf);
  requireAtLeast("swayPositionSd_m", swayPositionSd_m, 0);
  requireAtLeast("swayYawSd_rad", swayYawSd_rad, 0);
  for (auto [name, period] : {std::pair{"swayPositionPeriod_s", swayPositionPeriod_s}, {"swayYawPeriod_s", swayYawPeriod_s}}) {
    requireFinite(name, period);
    if (!(period > 0)) fail(name, "a period above 0 seconds", fmt::format("{}", period));
  }
  for (auto [name, damping] : {std::pair{"swayPositionDamping", swayPositionDamping}, {"swayYawDamping", swayYawDamping}}) {
    requireFinite(name, damping);
    if (!(damping >= 0 && damping < 1)) fail(name, "a damping ratio in [0, 1)", fmt::format("{}", damping));
  }
  for (int i = 0; i < 3; ++i) requireFinite(fmt::format("centroid[{}]", i), centroid[i]);
  requireFinite("maxHitSpeed_mps", maxHitSpeed_mps);
  if (!(maxHitSpeed_mps > 0)) fail("maxHitSpeed_mps", "a speed above 0", fmt::format("{}", maxHitSpeed_mps));
  requireIn("hitActionFraction", hitActionFraction, 0, 1);
  requireAtLeast("minHitActionSeconds", minHitActionSeconds, 0);
  double weightSum = 0;
  for (std::size_t i = 0; i < punchCountWeights.size(); ++i) {
    requireAtLeast(fmt::format("punchCountWeights[{}]", i), punchCountWeights[i], 0);
    weightSum += punchCountWeights[i];
  }
  if (!(weightSum > 0)) fail("punchCountWeights", "at least one weight above 0", "all 0");
  requireDistribution("punchSeconds", punchSeconds, 0, kInf);
  requireIn("rightHandFraction", rightHandFraction, 0, 1);
  requireDistribution("hitAngle_rad[0]", hitAngle_rad[0], -M_PI, M_PI);
  requireDistribution("hitAngle_rad[1]", hitAngle_rad[1], -M_PI, M_PI);
  requireDistribution("hitDistance_m", hitDistance_m, 0, kInf);
  requireDistribution("hitHeight_m", hitHeight_m, -kInf, kInf);
  requireFinite("punchAngleRate_radps", punchAngleRate_radps);
  requireFinite("punchDistanceRate_mps", punchDistanceRate_mps);
  requireFinite("punchHeightRate_mps", punchHeightRate_mps);
  requireDistribution("hitWeight", hitWeight, 0, 1);
  if (!(hitWeight.min > 0))
    fail("hitWeight.min", "a weight above 0 (weights are in (0, 1])", fmt::format("{}", hitWeight.min));
}

StateActionModel makeSyntheticModel(const SyntheticModelSpec& spec) {
  spec.validate();
  Draw draw(spec.seed);
  const auto states = static_cast<std::uint32_t>(spec.states);
  const auto actions = static_cast<std::uint32_t>(spec.actions);
  const double dt = 1 / spec.fps;

  StateActionModel m;
  m.frameTime = dt;

  // Out-actions per state: one each (the cycle needs it), the rest by gamma weights.
  std::vector<double> weights(states);
  for (double& w : weights) w = draw.gammaMeanOne(spec.outDegreeCv);
  const std::vector<std::uint32_t> extra = apportion(actions - states, weights);
  m.stateActionBegin.assign(states + 1, 0);
  for (std::uint32_t s = 0; s < states; ++s) m.stateActionBegin[s + 1] = m.stateActionBegin[s] + 1 + extra[s];

  // End states: the cycle action of each state (at a random place among its actions) goes to
  // the next state; the others to states drawn by popularity, never back to where they start
  // (the boxing graph has no such action).
  std::vector<double> popularity(states);
  for (double& w : popularity) w = draw.gammaMeanOne(spec.inDegreeCv);
  std::partial_sum(popularity.begin(), popularity.end(), popularity.begin());
  auto drawState = [&]() {
    const double u = draw.uniform() * popularity.back();
    const auto it = std::upper_bound(popularity.begin(), popularity.end(), u);
    return static_cast<std::uint32_t>(std::min<std::ptrdiff_t>(it - popularity.begin(), states - 1));
  };
  std::vector<std::uint32_t> cycleAction(states);
  m.actionFrom.resize(actions);
  m.actionTo.resize(actions);
  std::vector<std::uint32_t> length(actions);
  for (std::uint32_t s = 0; s < states; ++s) {
    const std::uint32_t begin = m.stateActionBegin[s], end = m.stateActionBegin[s + 1];
    cycleAction[s] = begin + static_cast<std::uint32_t>(draw.below(end - begin));
    for (std::uint32_t a = begin; a < end; ++a) {
      m.actionFrom[a] = s;
      length[a] = spec.minFrames + static_cast<std::uint32_t>(draw.below(spec.maxFrames - spec.minFrames + 1));
      if (a == cycleAction[s]) {
        m.actionTo[a] = (s + 1) % states;
        continue;
      }
      std::uint32_t to = drawState();
      for (int attempt = 0; to == s && states > 1; ++attempt)
        to = attempt < 64 ? drawState() : (s + 1 + static_cast<std::uint32_t>(draw.below(states - 1))) % states;
      m.actionTo[a] = to;
    }
  }

  // Frames, state by state: the run of the cycle action arriving here, the state's frame
  // (one clip), then the runs of this state's other actions (one clip each).
  std::uint64_t total = states;
  for (std::uint32_t a = 0; a < actions; ++a) total += length[a] - 1;
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw Error(fmt::format("synthetic model: expected at most 2^32 - 1 frames, found {} ({} actions of up to {} frames)",
                            total, actions, spec.maxFrames));
  m.framesTotal = static_cast<std::uint32_t>(total);
  std::vector<std::uint32_t> runStart(actions);
  m.stateFrame.resize(states);
  std::uint32_t next = 0;
  for (std::uint32_t s = 0; s < states; ++s) {
    const std::uint32_t arriving = cycleAction[(s + states - 1) % states];
    m.clipOffset.push_back(next);
    runStart[arriving] = next;
    next += length[arriving] - 1;
    m.stateFrame[s] = next++;
    for (std::uint32_t a = m.stateActionBegin[s]; a < m.stateActionBegin[s + 1]; ++a) {
      if (a == cycleAction[s]) continue;
      runStart[a] = next;
      if (length[a] > 1) m.clipOffset.push_back(next);
      next += length[a] - 1;
    }
  }
  m.clipOffset.push_back(next);
  m.componentFrames.resize(m.framesTotal);
  std::iota(m.componentFrames.begin(), m.componentFrames.end(), 0u);

  std::vector<Transition> edges;
  edges.reserve(2 * static_cast<std::size_t>(actions));
  const std::size_t frameCount = total - states + actions;
  m.actionFrames.reserve(frameCount);
  m.frameEntersTransition.reserve(frameCount);
  m.actionFrameBegin.assign(1, 0);
  for (std::uint32_t a = 0; a < actions; ++a) {
    const std::uint32_t from = m.stateFrame[m.actionFrom[a]], to = m.stateFrame[m.actionTo[a]];
    const bool runsIntoEnd = a == cycleAction[m.actionFrom[a]] && length[a] > 1;
    for (std::uint32_t k = 0; k + 1 < length[a]; ++k) {
      m.actionFrames.push_back(runStart[a] + k);
      m.frameEntersTransition.push_back(k == 0 ? 1 : 0);
    }
    m.actionFrames.push_back(to);
    m.frameEntersTransition.push_back(runsIntoEnd ? 0 : 1);
    m.actionFrameBegin.push_back(static_cast<std::uint32_t>(m.actionFrames.size()));
    edges.push_back({from, m.actionFrames[m.actionFrameBegin[a]]});
    if (length[a] > 1 && !runsIntoEnd) edges.push_back({runStart[a] + length[a] - 2, to});
  }
  // Two one-frame actions between the same states are one edge of the frame graph.
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (const Transition& e : edges) {
    m.transitions.push_back(e.from);
    m.transitions.push_back(e.to);
    m.transitionDistance.push_back(static_cast<float>(draw.bounded(spec.transitionDistance)));
  }

  // Root motion per action frame: drift in the avatar frame plus sway in the decision's.
  const Sway swayPosition(spec.swayPositionSd_m, spec.swayPositionPeriod_s, spec.swayPositionDamping, dt);
  const Sway swayYaw(spec.swayYawSd_rad, spec.swayYawPeriod_s, spec.swayYawDamping, dt);
  const Eigen::Vector3d centroid(spec.centroid[0], spec.centroid[1], spec.centroid[2]);
  for (int i = 0; i < 3; ++i) m.centroid[i] = spec.centroid[i];
  m.frameRoot.resize(3 * frameCount);
  m.frameCentroid.resize(3 * frameCount);
  m.actionDisplacement.resize(3 * static_cast<std::size_t>(actions));
  for (std::uint32_t a = 0; a < actions; ++a) {
    const std::size_t begin = m.actionFrameBegin[a], n = length[a];
    double* root = m.frameRoot.data() + 3 * begin;
    swayPosition.run(draw, n, root, 3);
    swayPosition.run(draw, n, root + 1, 3);
    swayYaw.run(draw, n, root + 2, 3);
    const GroundMotion step{draw.bounded(spec.driftSideways_mps) * dt, draw.bounded(spec.driftForward_mps) * dt,
                            draw.bounded(spec.driftTurn_radps) * dt};
    GroundMotion drift;
    for (std::size_t k = 0; k < n; ++k) {
      drift = compose(drift, step);
      double* r = root + 3 * k;
      r[0] += drift.dx;
      r[1] += drift.dz;
      r[2] = std::remainder(r[2] + drift.dyaw, 2 * M_PI);
      const Eigen::Vector3d c = transformPoint({r[0], r[1], r[2]}, centroid);
      float* out = m.frameCentroid.data() + 3 * (begin + k);
      out[0] = static_cast<float>(c.x());
      out[1] = static_cast<float>(c.y());
      out[2] = static_cast<float>(c.z());
    }
    std::copy(root + 3 * (n - 1), root + 3 * n, m.actionDisplacement.begin() + 3 * a);
  }

  // Which actions hold hits: the long enough ones, as many as the fraction asks for.
  m.maxHitSpeed_mps = spec.maxHitSpeed_mps;
  std::vector<std::uint32_t> eligible;
  for (std::uint32_t a = 0; a < actions; ++a)
    if (length[a] * dt >= spec.minHitActionSeconds - 1e-9) eligible.push_back(a);
  const auto wanted = std::min<std::size_t>(
      eligible.size(), static_cast<std::size_t>(std::llround(spec.hitActionFraction * static_cast<double>(actions))));
  for (std::size_t i = 0; i < wanted; ++i) std::swap(eligible[i], eligible[i + draw.below(eligible.size() - i)]);
  std::vector<std::uint8_t> hasHits(actions, 0);
  for (std::size_t i = 0; i < wanted; ++i) hasHits[eligible[i]] = 1;

  const double punchWeightSum =
      std::accumulate(spec.punchCountWeights.begin(), spec.punchCountWeights.end(), 0.0);
  std::vector<ActionHit> local;
  m.actionHitBegin.assign(1, 0);
  for (std::uint32_t a = 0; a < actions; ++a) {
    if (hasHits[a]) {
      local.clear();
      double u = draw.uniform() * punchWeightSum;
      std::size_t punches = 1;
      for (; punches < spec.punchCountWeights.size() && u >= spec.punchCountWeights[punches - 1]; ++punches)
        u -= spec.punchCountWeights[punches - 1];
      for (std::size_t p = 0; p < punches; ++p) {
        const auto hand = static_cast<std::uint8_t>(draw.uniform() < spec.rightHandFraction ? 1 : 0);
        const auto frames = static_cast<std::uint32_t>(std::clamp<long long>(
            std::llround(draw.bounded(spec.punchSeconds) * spec.fps), 1, length[a]));
        const auto first = 1 + static_cast<std::uint32_t>(draw.below(length[a] - frames + 1));
        // The punch's middle frame is drawn; the others follow at the measured rates, all
        // inside the bounds (which the hit grid takes as its volume).
        const double half = 0.5 * (frames - 1) * dt;
        const double angle = draw.bounded(spec.hitAngle_rad[hand], half * std::abs(spec.punchAngleRate_radps),
                                          half * std::abs(spec.punchAngleRate_radps));
        const double distance = draw.bounded(spec.hitDistance_m, half * std::abs(spec.punchDistanceRate_mps),
                                             half * std::abs(spec.punchDistanceRate_mps));
        const double height = draw.bounded(spec.hitHeight_m, half * std::abs(spec.punchHeightRate_mps),
                                           half * std::abs(spec.punchHeightRate_mps));
        for (std::uint32_t k = 0; k < frames; ++k) {
          const double t = k * dt - half;
          const double th = std::clamp(angle + t * spec.punchAngleRate_radps, spec.hitAngle_rad[hand].min,
                                       spec.hitAngle_rad[hand].max);
          const double d = std::clamp(distance + t * spec.punchDistanceRate_mps, spec.hitDistance_m.min,
                                      spec.hitDistance_m.max);
          const double y = std::clamp(height + t * spec.punchHeightRate_mps, spec.hitHeight_m.min,
                                      spec.hitHeight_m.max);
          local.push_back({a, first + k, hand, static_cast<float>(d * std::sin(th)), static_cast<float>(y),
                           static_cast<float>(d * std::cos(th)), static_cast<float>(draw.bounded(spec.hitWeight))});
        }
      }
      // One hitting point per hand and frame; overlapping punches keep the earlier draw.
      std::stable_sort(local.begin(), local.end(), [](const ActionHit& x, const ActionHit& y) {
        return std::tie(x.offset, x.hand) < std::tie(y.offset, y.hand);
      });
      local.erase(std::unique(local.begin(), local.end(),
                              [](const ActionHit& x, const ActionHit& y) {
                                return x.offset == y.offset && x.hand == y.hand;
                              }),
                  local.end());
      m.hits.insert(m.hits.end(), local.begin(), local.end());
    }
    m.actionHitBegin.push_back(static_cast<std::uint32_t>(m.hits.size()));
  }
  return m;
}

}  // namespace mgrl
