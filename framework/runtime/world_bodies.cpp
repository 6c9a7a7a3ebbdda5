// The world's body collisions: torso capsules, decisions that keep bodies apart,
// and pushes for what still overlaps (world.hpp; the rest of the world is in world.cpp).
#include <algorithm>
#include <cmath>

#include "mgrl/motion/kinematics.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/runtime/world_parts.hpp"

namespace mgrl {

using namespace world_detail;  // NOLINT: the world's own helpers (world_parts.hpp)

// ---------------------------------------------------------------------------------------
// Body collisions: a torso capsule per avatar, from the pelvis to the head.
// Decisions rule out actions whose root path would run into another body within the
// look-ahead, assuming the others finish the actions they are playing and then stand;
// what still overlaps is pushed apart over the next frames. Neighbours come from a hashed
// grid of cells `reach_` wide, so the cost stays linear in the number of avatars.

void World::snapshot() {
  const bool bodies = setup_.params.bodyRadius > 0;
  for (std::size_t i = 0; i < avatars_.size(); ++i) {
    const Avatar& a = avatars_[i];
    Track& t = tracks_[i];
    if (t.decision.dyaw != a.decision.dyaw || t.length == 0) {  // a sine and cosine per decision, not per frame
      t.c = std::cos(a.decision.dyaw);
      t.s = std::sin(a.decision.dyaw);
    }
    t.decision = a.decision;
    t.action = a.action;
    t.step = a.step;
    t.length = a.length;
    if (bodies && a.length > 0)
      t.now = place(a.decision, t.c, t.s, model_.actionFrameBegin[a.action] + a.step - 1);
    else
      t.now = {bodyPoint(i, BodyTable::Pelvis), bodyPoint(i, BodyTable::Head)};
  }
  if (bodies) buildGrid();
}

// The torso at action frame k of an action started in avatar frame `at` (c, s: its yaw's
// cosine and sine), as transformPoint() would place it.
World::Segment World::place(const GroundMotion& at, double c, double s, std::size_t k) const {
  const float* b = actionBody_.data() + 6 * k;
  return {{at.dx + c * b[0] + s * b[2], b[1], at.dz - s * b[0] + c * b[2]},
          {at.dx + c * b[3] + s * b[5], b[4], at.dz - s * b[3] + c * b[5]}};
}

void World::buildGrid() {
  const std::size_t n = avatars_.size();
  std::size_t buckets = 1;
  while (buckets < 2 * n) buckets <<= 1;
  gridStart_.assign(buckets + 1, 0);
  gridItems_.resize(n);
  gridCell_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& q = tracks_[i].now.pelvis;
    gridCell_[i] = packCell(static_cast<std::int64_t>(std::floor(q.x() / reach_)),
                            static_cast<std::int64_t>(std::floor(q.z() / reach_)));
    ++gridStart_[cellBucket(gridCell_[i], buckets - 1) + 1];
  }
  for (std::size_t b = 0; b < buckets; ++b) gridStart_[b + 1] += gridStart_[b];
  std::vector<std::uint32_t>& fill = gridItems_;  // counting sort, avatars in index order per bucket
  thread_local std::vector<std::uint32_t> cursor;
  cursor.assign(gridStart_.begin(), gridStart_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) fill[cursor[cellBucket(gridCell_[i], buckets - 1)]++] = static_cast<std::uint32_t>(i);
}

// Calls visit(j) for every avatar j whose pelvis is in the 3 x 3 cells around `at` (and a
// few others sharing their buckets), in a fixed order.
template <class F>
void World::forNeighbours(const Eigen::Vector3d& at, F&& visit) const {
  const std::size_t mask = gridStart_.size() - 2;
  const auto cx = static_cast<std::int64_t>(std::floor(at.x() / reach_));
  const auto cz = static_cast<std::int64_t>(std::floor(at.z() / reach_));
  std::array<std::size_t, 9> seen{};
  int count = 0;
  for (std::int64_t dx = -1; dx <= 1; ++dx)
    for (std::int64_t dz = -1; dz <= 1; ++dz) {
      const std::size_t b = cellBucket(packCell(cx + dx, cz + dz), mask);
      if (std::find(seen.begin(), seen.begin() + count, b) != seen.begin() + count) continue;
      seen[static_cast<std::size_t>(count++)] = b;
      for (std::uint32_t k = gridStart_[b]; k < gridStart_[b + 1]; ++k) visit(static_cast<std::size_t>(gridItems_[k]));
    }
}

World::Segment World::predict(std::size_t j, std::uint32_t ahead) const {
  const Track& t = tracks_[j];
  if (t.length == 0) return t.now;
  const std::uint32_t shown = std::min(t.step + ahead, t.length);  // then it stands
  return place(t.decision, t.c, t.s, model_.actionFrameBegin[t.action] + shown - 1);
}

// allowed[j] for the j-th action leaving avatar i's state: its torso keeps clear of every
// other torso at each checked frame of the look-ahead, or at least does not get closer
// than it is now. When no action qualifies, only the one keeping the most room. Left empty
// when no other body is within reach (every action allowed).
void World::restrictActions(std::size_t i, std::vector<std::uint8_t>& allowed) {
  allowed.clear();
  const Avatar& a = avatars_[i];
  const double gap = 2 * setup_.params.bodyRadius;
  thread_local std::vector<std::uint32_t> near;
  near.clear();
  const Eigen::Vector3d& me = tracks_[i].now.pelvis;
  double room = std::numeric_limits<double>::infinity();  // clearance now
  forNeighbours(me, [&](std::size_t j) {
    if (j == i) return;
    const Segment& other = tracks_[j].now;
    if (std::hypot(other.pelvis.x() - me.x(), other.pelvis.z() - me.z()) > reach_) return;
    near.push_back(static_cast<std::uint32_t>(j));
    room = std::min(room, torsoDistance(me, tracks_[i].now.head, other.pelvis, other.head) - gap);
  });
  if (near.empty()) return;
  const std::uint32_t begin = model_.stateActionBegin[a.state], end = model_.stateActionBegin[a.state + 1];
  allowed.assign(end - begin, 0);
  thread_local std::vector<double> clearance;
  clearance.assign(end - begin, std::numeric_limits<double>::infinity());
  // The others' torsos at each frame of the look-ahead, once for all candidate actions.
  thread_local std::vector<Segment> future;
  future.resize(near.size() * aheadFrames_);
  for (std::size_t n = 0; n < near.size(); ++n)
    for (std::uint32_t t = 0; t < aheadFrames_; ++t) future[n * aheadFrames_ + t] = predict(near[n], t + 1);
  const double c = std::cos(a.decision.dyaw), sn = std::sin(a.decision.dyaw);
  const double floor = std::min(0.0, room - 1e-3);
  bool any = false;
  for (std::uint32_t act = begin; act < end; ++act) {
    const std::uint32_t checked = std::min<std::uint32_t>(static_cast<std::uint32_t>(model_.actionLength(act)), aheadFrames_);
    double worst = std::numeric_limits<double>::infinity();
    // Every other frame, and the last one checked (checked >= 1: actions have a frame).
    for (std::uint32_t t = 0; worst >= floor; t = std::min(t + 2, checked - 1)) {
      const Segment mine = place(a.decision, c, sn, model_.actionFrameBegin[act] + t);
      for (std::size_t n = 0; n < near.size(); ++n) {
        const Segment& other = future[n * aheadFrames_ + t];
        worst = std::min(worst, torsoDistance(mine.pelvis, mine.head, other.pelvis, other.head) - gap);
      }
      if (t == checked - 1) break;
    }
    clearance[act - begin] = worst;
    if (worst >= floor) {
      allowed[act - begin] = 1;
      any = true;
    }
  }
  auto& counts = bodyCounts_[i];
  if (!any) {
    ++counts[1];
    allowed[static_cast<std::size_t>(std::max_element(clearance.begin(), clearance.end()) - clearance.begin())] = 1;
  } else if (std::find(allowed.begin(), allowed.end(), std::uint8_t{0}) != allowed.end()) {
    ++counts[0];
  }
}

// Pushes overlapping torsos apart along the floor, half each: by separation_speed per
// second, and at once by whatever brings them under 2 * body_radius - 0.04 m (never closer
// than that, whatever they do). Pushes are found from where every avatar is, then applied
// together (to the avatar frames, the poses about to be made, and the snapshot), in avatar
// order.
void World::separate() {
  const WorldParams& p = setup_.params;
  const double gap = 2 * p.bodyRadius, step = p.separationSpeed * model_.frameTime;
  const double slack = std::min(0.04, 0.5 * gap);
  for (std::size_t i = 0; i < avatars_.size(); ++i) {
    const Segment& mine = tracks_[i].now;
    forNeighbours(mine.pelvis, [&](std::size_t j) {
      if (j <= i) return;
      const Segment& other = tracks_[j].now;
      if (std::hypot(mine.pelvis.x() - other.pelvis.x(), mine.pelvis.z() - other.pelvis.z()) > gap + 2 * lean_) return;
      const double overlap = gap - torsoDistance(mine.pelvis, mine.head, other.pelvis, other.head);
      if (overlap <= 0) return;
      Eigen::Vector2d away(mine.pelvis.x() - other.pelvis.x(), mine.pelvis.z() - other.pelvis.z());
      if (away.norm() < 1e-6) away = Eigen::Vector2d(std::cos(tracks_[i].decision.dyaw), -std::sin(tracks_[i].decision.dyaw));
      away.normalize();
      const double move = 0.5 * std::max(std::min(overlap, step), overlap - slack);
      pending_[i] += move * away;
      pending_[j] -= move * away;
      ++pushes_;
    });
  }
  bool moved = false;
  for (std::size_t i = 0; i < avatars_.size(); ++i) {
    Eigen::Vector2d& push = pending_[i];
    if (push.x() == 0 && push.y() == 0) continue;
    moved = true;
    Avatar& a = avatars_[i];
    a.decision.dx += push.x();
    a.decision.dz += push.y();
    a.now.dx += push.x();
    a.now.dz += push.y();
    if (a.playback) a.playback->nudge(push.x(), push.y());
    Track& t = tracks_[i];
    t.decision = a.decision;
    for (Eigen::Vector3d* q : {&t.now.pelvis, &t.now.head}) {
      q->x() += push.x();
      q->z() += push.y();
    }
    push.setZero();
  }
  if (moved) buildGrid();  // the next decisions look for neighbours where they now are
}

}  // namespace mgrl
