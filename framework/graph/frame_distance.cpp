#include "mgrl/graph/frame_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "mgrl/motion/kinematics.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/rotation.hpp"

namespace mgrl {

namespace {

// Rows of the distance matrix computed together: each band recomputes one row above and
// below for the local-minimum test, so larger bands waste less, smaller ones use less memory.
constexpr std::size_t kBandRows = 32;
// A graph with more candidate transitions than this is certainly a threshold mistake.
constexpr std::size_t kMaxTransitions = 50'000'000;

// Adds weight * theta^2 for every column, theta = 2 acos|a . q_c| the geodesic angle
// between unit quaternions. acos(x) on [0, 1] is sqrt(1 - x) times a cubic (Abramowitz &
// Stegun 4.4.45, absolute error below 7e-5 rad), so theta^2 = 4 (1 - x) cubic^2 needs no
// square root and no branch: the loop vectorises. A dot product rounded above 1 gives a
// tiny negative term; the caller clamps the total at 0.
void addGeodesic2(float* __restrict row, const float* __restrict qx, const float* __restrict qy,
                  const float* __restrict qz, const float* __restrict qw, float ax, float ay, float az, float aw,
                  float weight, std::size_t count) {
  const float w4 = 4.0f * weight;
  for (std::size_t c = 0; c < count; ++c) {
    const float x = std::fabs(ax * qx[c] + ay * qy[c] + az * qz[c] + aw * qw[c]);
    const float p = 1.5707288f + x * (-0.2121144f + x * (0.0742610f + x * -0.0187293f));
    row[c] += w4 * (1.0f - x) * p * p;
  }
}

// Angular velocity (rad/s, in the rotation's own frame) between two orientations dt apart.
Eigen::Vector3d angularVelocity(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double dt) {
  Eigen::Quaterniond d = a.conjugate() * b;
  if (d.w() < 0) d.coeffs() = -d.coeffs();
  const Eigen::AngleAxisd aa(d.normalized());
  return aa.axis() * (aa.angle() / dt);
}

}  // namespace

FrameFeatures computeFrameFeatures(const MotionDatabase& db, const GraphParams& params) {
  const Skeleton& skeleton = *db.skeleton;
  for (const auto& [name, weight] : params.jointWeights)
    if (skeleton.find(name) < 0)
      throw Error(fmt::format("graph.joint_weights: expected a joint of the skeleton ({}), found '{}'",
                              skeleton.jointList(), name));
  auto weightOf = [&](std::size_t j) {
    const auto it = params.jointWeights.find(skeleton.joint(j).name);
    return it != params.jointWeights.end() ? it->second : defaultJointWeight(skeleton.joint(j).name);
  };

  FrameFeatures f;
  f.frames = db.frameCount();
  std::vector<double> raw;
  for (std::size_t j = 0; j < skeleton.jointCount(); ++j) {
    const double w = weightOf(j);
    if (w > 0 || j == 0) {  // slot 0 is always the root, even with weight 0
      f.joints.push_back(static_cast<int>(j));
      raw.push_back(w);
    }
  }
  double total = 0;
  for (double w : raw) total += w;
  if (total <= 0) throw Error("graph.joint_weights: expected at least one joint with a positive weight, found none");
  for (double w : raw) f.weight.push_back(static_cast<float>(w / total));

  const std::size_t slots = f.joints.size();
  const std::size_t n = f.frames;
  f.quat.assign(slots * 4 * n, 0.0f);
  // Linear features: per slot an angular velocity (3), then the root's ground velocity in
  // the avatar frame (3), yaw rate (1) and height above the ground (1).
  const std::size_t dims = slots * 3 + 5;
  f.linear.setZero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(dims));

  std::vector<Eigen::Quaterniond> frameRot(n * slots);
  for (std::size_t c = 0; c < db.clips.size(); ++c) {
    const Clip& clip = db.clips[c];
    const std::size_t count = clip.motion.frameCount();
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t g = db.offsets[c] + k;
      for (std::size_t s = 0; s < slots; ++s) {
        Eigen::Quaterniond q = clip.motion.rotation(k, static_cast<std::size_t>(f.joints[s]));
        // The root's facing yaw is factored out: what remains is its tilt (pitch and roll).
        if (s == 0) q = axisRotation(Axis::Y, -clip.annotation.frames[k].yaw) * q;
        q.normalize();
        frameRot[g * slots + s] = q;
        f.quat[(s * 4 + 0) * n + g] = static_cast<float>(q.x());
        f.quat[(s * 4 + 1) * n + g] = static_cast<float>(q.y());
        f.quat[(s * 4 + 2) * n + g] = static_cast<float>(q.z());
        f.quat[(s * 4 + 3) * n + g] = static_cast<float>(q.w());
      }
    }
    const double dt = db.frameTime;
    const double nu = params.velocityWeight;
    const int rootJoint = 0;
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t g = db.offsets[c] + k;
      // Central differences inside the clip, one-sided at its ends.
      const std::size_t a = k > 0 ? k - 1 : k;
      const std::size_t b = k + 1 < count ? k + 1 : k;
      const double span = static_cast<double>(b - a) * dt;
      auto row = f.linear.row(static_cast<Eigen::Index>(g));
      if (span > 0 && nu > 0) {
        for (std::size_t s = 0; s < slots; ++s) {
          const Eigen::Vector3d w = angularVelocity(frameRot[(db.offsets[c] + a) * slots + s],
                                                    frameRot[(db.offsets[c] + b) * slots + s], span);
          const double scale = nu * std::sqrt(static_cast<double>(f.weight[s]));
          for (int i = 0; i < 3; ++i) row(static_cast<Eigen::Index>(s * 3 + i)) = static_cast<float>(scale * w[i]);
        }
        // The root's travel and turn, seen from the avatar: yaw-invariant.
        const AvatarFrame& fa = clip.annotation.frames[a];
        const AvatarFrame& fb = clip.annotation.frames[b];
        const Eigen::Vector3d v = fa.toAvatar(fb.origin) / span;
        double turn = fb.yaw - fa.yaw;
        turn = std::remainder(turn, 2 * M_PI) / span;
        const double rootScale = nu * std::sqrt(static_cast<double>(f.weight[0]));
        row(static_cast<Eigen::Index>(slots * 3 + 0)) = static_cast<float>(rootScale * v.x());
        row(static_cast<Eigen::Index>(slots * 3 + 1)) = static_cast<float>(rootScale * v.z());
        row(static_cast<Eigen::Index>(slots * 3 + 2)) = static_cast<float>(rootScale * turn);
      }
      const double height = clip.motion.localTranslation(k, rootJoint).y() - clip.annotation.groundY;
      const double vertical = (clip.motion.localTranslation(b, rootJoint).y() - clip.motion.localTranslation(a, rootJoint).y()) /
                              std::max(span, dt);
      row(static_cast<Eigen::Index>(slots * 3 + 3)) =
          static_cast<float>(nu * std::sqrt(static_cast<double>(f.weight[0])) * vertical);
      row(static_cast<Eigen::Index>(slots * 3 + 4)) = static_cast<float>(params.rootHeightWeight * height);
    }
  }
  f.linearNorm2.resize(n);
  for (std::size_t g = 0; g < n; ++g) f.linearNorm2[g] = f.linear.row(static_cast<Eigen::Index>(g)).squaredNorm();
  return f;
}

double frameDistance2(const FrameFeatures& f, std::uint32_t a, std::uint32_t b) {
  const std::size_t n = f.frames;
  double sum = 0;
  for (std::size_t s = 0; s < f.joints.size(); ++s) {
    double dot = 0;
    for (int i = 0; i < 4; ++i)
      dot += static_cast<double>(f.quat[(s * 4 + i) * n + a]) * static_cast<double>(f.quat[(s * 4 + i) * n + b]);
    const double theta = 2 * std::acos(std::min(1.0, std::abs(dot)));
    sum += f.weight[s] * theta * theta;
  }
  const auto ra = f.linear.row(a).cast<double>();
  const auto rb = f.linear.row(b).cast<double>();
  return sum + (ra - rb).squaredNorm();
}

std::vector<std::int8_t> contactEvents(const MotionDatabase& db, ContactEvent event) {
  std::vector<std::int8_t> result(db.frameCount(), -1);
  for (std::size_t c = 0; c < db.clips.size(); ++c) {
    const auto& left = db.clips[c].annotation.contact[0];
    const auto& right = db.clips[c].annotation.contact[1];
    const std::size_t count = db.clips[c].motion.frameCount();
    for (std::size_t k = 0; k + 1 < count; ++k) {
      std::int8_t kind = -1;
      switch (event) {
        case ContactEvent::None: kind = 0; break;
        case ContactEvent::LeftFootLiftoff:
          if (left[k] && !left[k + 1]) kind = 0;
          break;
        case ContactEvent::AnyContactChange:
          if (left[k] && !left[k + 1]) kind = 0;
          else if (!left[k] && left[k + 1]) kind = 1;
          else if (right[k] && !right[k + 1]) kind = 2;
          else if (!right[k] && right[k + 1]) kind = 3;
          break;
      }
      result[db.offsets[c] + k] = kind;
    }
  }
  return result;
}

std::vector<std::uint32_t> standingCutFrames(const MotionDatabase& db, const FrameFeatures& f) {
  const std::size_t n = f.frames;
  // Angular motion from each frame to the next (a clip's last frame: none, never a cut).
  std::vector<double> motion(n, std::numeric_limits<double>::infinity());
  for (std::size_t c = 0; c < db.clips.size(); ++c)
    for (std::uint32_t g = db.offsets[c]; g + 1 < db.offsets[c + 1]; ++g) {
      double sum = 0;
      for (std::size_t s = 0; s < f.joints.size(); ++s) {
        double dot = 0;
        for (int i = 0; i < 4; ++i)
          dot +=
              static_cast<double>(f.quat[(s * 4 + i) * n + g]) * static_cast<double>(f.quat[(s * 4 + i) * n + g + 1]);
        const double theta = 2 * std::acos(std::min(1.0, std::abs(dot)));
        sum += f.weight[s] * theta * theta;
      }
      motion[g] = sum;
    }
  std::vector<std::uint32_t> cuts;
  for (std::size_t c = 0; c < db.clips.size(); ++c) {
    const Annotation& a = db.clips[c].annotation;
    const auto count = static_cast<std::ptrdiff_t>(db.clips[c].motion.frameCount());
    const auto half = static_cast<std::ptrdiff_t>(std::lround(GraphParams::kStandingCutSpacing_s / db.frameTime));
    const std::uint32_t offset = db.offsets[c];
    for (std::ptrdiff_t k = 0; k + 1 < count; ++k) {
      bool planted = true, least = true;
      const double own = motion[offset + static_cast<std::size_t>(k)];
      // The window ends with the clip: a clip's first and last still moments are where it
      // is entered and left.
      for (std::ptrdiff_t j = std::max<std::ptrdiff_t>(0, k - half);
           j <= std::min(count - 1, k + half) && planted && least; ++j) {
        const auto u = static_cast<std::size_t>(j);
        planted = a.contact[0][u] && a.contact[1][u];
        const double other = motion[offset + u];
        least = j < k ? own < other : own <= other;
      }
      if (planted && least && std::isfinite(own)) cuts.push_back(offset + static_cast<std::uint32_t>(k));
    }
  }
  return cuts;
}

namespace {

// One contact-event class: its frames gathered so that the kernels stream contiguous memory.
struct EventGroup {
  std::vector<std::uint32_t> frame;       // global frame of each member, ascending
  std::vector<std::uint32_t> clip;        // its clip
  std::vector<float> quat;                // (slot * 4 + component) * size + member
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> linear;
  std::vector<float> linearNorm2;
};

EventGroup gather(const MotionDatabase& db, const FrameFeatures& f, std::span<const std::uint32_t> members) {
  EventGroup g;
  const std::size_t m = members.size();
  g.frame.assign(members.begin(), members.end());
  g.clip.resize(m);
  for (std::size_t i = 0; i < m; ++i) g.clip[i] = static_cast<std::uint32_t>(db.clipOf(members[i]));
  const std::size_t comps = f.joints.size() * 4;
  g.quat.resize(comps * m);
  for (std::size_t c = 0; c < comps; ++c)
    for (std::size_t i = 0; i < m; ++i) g.quat[c * m + i] = f.quat[c * f.frames + members[i]];
  g.linear.resize(static_cast<Eigen::Index>(m), f.linear.cols());
  g.linearNorm2.resize(m);
  for (std::size_t i = 0; i < m; ++i) {
    g.linear.row(static_cast<Eigen::Index>(i)) = f.linear.row(members[i]);
    g.linearNorm2[i] = f.linearNorm2[members[i]];
  }
  return g;
}

// Squared distances of rows [first, first + count) of the group against every member,
// into out (count x m, row-major).
void distanceRows(const EventGroup& g, const FrameFeatures& f, std::size_t first, std::size_t count,
                  std::vector<float>& out) {
  const std::size_t m = g.frame.size();
  out.assign(count * m, 0.0f);
  // Velocity and height: |a - b|^2 = |a|^2 + |b|^2 - 2 a.b, the cross terms as one product.
  Eigen::Map<Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> block(
      out.data(), static_cast<Eigen::Index>(count), static_cast<Eigen::Index>(m));
  block.noalias() = -2.0f * g.linear.middleRows(static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(count)) *
                    g.linear.transpose();
  for (std::size_t r = 0; r < count; ++r) {
    float* row = out.data() + r * m;
    const float own = g.linearNorm2[first + r];
    for (std::size_t c = 0; c < m; ++c) row[c] += own + g.linearNorm2[c];
    for (std::size_t s = 0; s < f.joints.size(); ++s) {
      const float* qx = g.quat.data() + (s * 4 + 0) * m;
      const float* qy = g.quat.data() + (s * 4 + 1) * m;
      const float* qz = g.quat.data() + (s * 4 + 2) * m;
      const float* qw = g.quat.data() + (s * 4 + 3) * m;
      const std::size_t i = first + r;
      addGeodesic2(row, qx, qy, qz, qw, qx[i], qy[i], qz[i], qw[i], f.weight[s], m);
    }
    for (std::size_t c = 0; c < m; ++c) row[c] = std::max(0.0f, row[c]);
  }
}

}  // namespace

std::vector<TransitionCandidate> findTransitions(const MotionDatabase& db, const FrameFeatures& features,
                                                 const GraphParams& params, TransitionSearchStats* stats) {
  params.validate();
  std::vector<std::int8_t> events = contactEvents(db, params.contactEvent);
  std::int8_t classes = 0;
  for (std::int8_t e : events) classes = std::max<std::int8_t>(classes, static_cast<std::int8_t>(e + 1));
  TransitionSearchStats local;
  if (params.standingCutsFor(db.frameCount() * db.frameTime)) {
    const std::int8_t standing = classes;
    for (std::uint32_t g : standingCutFrames(db, features))
      if (events[g] < 0) {
        events[g] = standing;
        classes = static_cast<std::int8_t>(standing + 1);
        ++local.standingCutFrames;
      }
  }
  const unsigned threads = params.threads ? params.threads : defaultThreadCount();
  const float limit2 = static_cast<float>(params.threshold * params.threshold);

  std::vector<TransitionCandidate> result;
  for (std::int8_t cls = 0; cls < classes; ++cls) {
    std::vector<std::uint32_t> members;
    for (std::uint32_t g = 0; g < events.size(); ++g)
      if (events[g] == cls) members.push_back(g);
    const std::size_t m = members.size();
    local.eventFrames += m;
    local.pairs += m * m;
    if (m < 2) continue;
    const EventGroup group = gather(db, features, members);
    // Neighbours in the candidate grid: the previous and next member of the same clip.
    auto hasPrev = [&](std::size_t i) { return i > 0 && group.clip[i - 1] == group.clip[i]; };
    auto hasNext = [&](std::size_t i) { return i + 1 < m && group.clip[i + 1] == group.clip[i]; };

    const std::size_t bands = (m + kBandRows - 1) / kBandRows;
    std::vector<std::vector<TransitionCandidate>> found(bands);
    std::vector<std::size_t> below(bands, 0);
    std::vector<std::vector<float>> scratch(threads);
    parallelFor(bands, threads, [&](std::size_t band, unsigned worker) {
      const std::size_t r0 = band * kBandRows;
      const std::size_t r1 = std::min(m, r0 + kBandRows);
      const std::size_t first = r0 > 0 ? r0 - 1 : 0;
      const std::size_t last = std::min(m, r1 + 1);
      std::vector<float>& d = scratch[worker];
      distanceRows(group, features, first, last - first, d);
      auto at = [&](std::size_t r, std::size_t c) { return d[(r - first) * m + c]; };
      for (std::size_t r = r0; r < r1; ++r) {
        for (std::size_t c = 0; c < m; ++c) {
          const float v = at(r, c);
          if (!(v < limit2) || c == r) continue;
          ++below[band];
          if (params.localMinimum) {
            bool minimum = true;
            // Strictly smaller than neighbours before it, not larger than those after:
            // one winner on a plateau, chosen the same way every run.
            for (int dr = -1; dr <= 1 && minimum; ++dr) {
              if ((dr < 0 && !hasPrev(r)) || (dr > 0 && !hasNext(r))) continue;
              for (int dc = -1; dc <= 1; ++dc) {
                if ((dr == 0 && dc == 0) || (dc < 0 && !hasPrev(c)) || (dc > 0 && !hasNext(c))) continue;
                const float u = at(r + static_cast<std::size_t>(dr), c + static_cast<std::size_t>(dc));
                const bool before = dr < 0 || (dr == 0 && dc < 0);
                if (before ? !(v < u) : !(v <= u)) {
                  minimum = false;
                  break;
                }
              }
            }
            if (!minimum) continue;
          }
          found[band].push_back({group.frame[r], group.frame[c] + 1, std::sqrt(v)});
        }
      }
    });
    std::size_t total = result.size();
    for (std::size_t b = 0; b < bands; ++b) {
      total += found[b].size();
      local.belowThreshold += below[b];
    }
    if (total > kMaxTransitions)
      throw Error(fmt::format("graph.threshold: expected at most {} transitions, found {}: lower graph.threshold "
                              "(now {}) or use graph.local_minimum: true",
                              kMaxTransitions, total, params.threshold));
    result.reserve(total);
    for (auto& part : found) result.insert(result.end(), part.begin(), part.end());
  }
  std::sort(result.begin(), result.end(), [](const TransitionCandidate& a, const TransitionCandidate& b) {
    return a.from != b.from ? a.from < b.from : a.to < b.to;
  });
  if (stats) *stats = local;
  return result;
}

}  // namespace mgrl
