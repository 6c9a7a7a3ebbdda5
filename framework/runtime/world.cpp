#include "mgrl/runtime/world.hpp"
#include "mgrl/runtime/world_parts.hpp"

#include <algorithm>
#include <barrier>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <span>
#include <thread>
#include <utility>

#include <fmt/format.h>

#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/learning/environment_model.hpp"
#include "mgrl/motion/kinematics.hpp"

namespace mgrl {

using namespace world_detail;  // NOLINT: the world's own helpers (world_parts.hpp)

// ---------------------------------------------------------------------------------------
// World

namespace {

// Splits a seed into independent per-avatar seeds (splitmix64).
std::uint64_t mix(std::uint64_t seed, std::uint64_t i) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (i + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

namespace {
constexpr std::size_t kSourcePosesMinAvatars = 64;
}  // namespace

World::World(WorldSetup setup)
    : setup_(std::move(setup)), model_(*setup_.model), body_(*setup_.body) {
  if (setup_.record) setup_.poses = true;
  if (setup_.avatars == 0) throw Error("world: expected at least one avatar, found 0");
  if (model_.stateCount() == 0) throw Error("world: expected a model with states, found none");
  if (setup_.poses && setup_.db == nullptr) throw Error("world: poses need the motion database");
  if (!setup_.makeController) throw Error("world: expected a controller factory");
  aimPoint_ = setup_.params.aim == "chest" ? BodyTable::Chest : BodyTable::Head;
  centroidHeight_ = setup_.params.targetHeight >= 0 ? setup_.params.targetHeight : model_.centroid[1];
  if (setup_.poses) {
    // For a crowd, frames outside a blend are posed from the capture's kinematics done once
    // here. The table (boxing: 1,960 frames, 3.4 MB; SNU sparring: 12,242 frames, 15 MB)
    // costs a forward-kinematics pass per frame and a page fault per 4 KB at the start, which
    // 64 avatars win back within seconds; fewer avatars, which are cheap anyway, do without.
    if (setup_.sourcePoses && (setup_.sourcePoses->frameCount() != setup_.db->frameCount() ||
                               setup_.sourcePoses->joints != setup_.db->skeleton->jointCount()))
      throw Error(
          fmt::format("world: expected source poses of the motion database ({} frames x {} joints), found {} "
                      "x {}",
                      setup_.db->frameCount(), setup_.db->skeleton->jointCount(), setup_.sourcePoses->frameCount(),
                      setup_.sourcePoses->joints));
    if (setup_.avatars >= kSourcePosesMinAvatars)
      sourcePoses_ =
          setup_.sourcePoses ? setup_.sourcePoses : std::make_shared<const SourcePoses>(makeSourcePoses(*setup_.db));
    // Each struck part's reaction chain: up to 3 joints below the struck one and above the
    // pelvis, lowest first, and the joints each one's turn moves.
    const Skeleton& skeleton = *setup_.db->skeleton;
    for (int side = 0; side < 2; ++side) {  // a blocking arm turns at its own joints
      ReactionChain& chain =
          reactionChains_[static_cast<std::size_t>(side == 0 ? BodyPart::LeftArm : BodyPart::RightArm)];
      chain.struck = body_.fistJoint[side];
      chain.joints = body_.armJoints[side];
      for (const int j : chain.joints) chain.below.push_back(subtreeJoints(skeleton, j));
    }
    for (const BodyPart part : {BodyPart::Spine, BodyPart::Chest, BodyPart::Head}) {
      ReactionChain& chain = reactionChains_[static_cast<std::size_t>(part)];
      chain.struck = part == BodyPart::Head ? body_.headJoint : part == BodyPart::Chest ? body_.neckJoint : body_.chestJoint;
      for (int j = skeleton.joint(static_cast<std::size_t>(chain.struck)).parent;
           j > 0 && j != body_.pelvisJoint && chain.joints.size() < 3; j = skeleton.joint(static_cast<std::size_t>(j)).parent)
        chain.joints.push_back(j);
      std::reverse(chain.joints.begin(), chain.joints.end());
      for (const int j : chain.joints) chain.below.push_back(subtreeJoints(skeleton, j));
    }
  }
  avatars_.resize(setup_.avatars);
  targets_.resize(setup_.avatars);
  heads_.resize(setup_.avatars);
  roots_.resize(setup_.avatars);
  for (std::size_t i = 0; i < avatars_.size(); ++i) startAvatar(i);
  recordAims();
  tracks_.resize(avatars_.size());
  pending_.assign(avatars_.size(), Eigen::Vector2d::Zero());
  bodyCounts_.assign(avatars_.size(), {0, 0});
  const WorldParams& p = setup_.params;
  if (p.bodyRadius > 0) {
    // How far a pelvis can get from its avatar origin within the look-ahead: two bodies
    // farther apart than twice that plus their radii cannot meet before the next check.
    aheadFrames_ = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(std::ceil(p.avoidSeconds / model_.frameTime)));
    actionBody_.resize(model_.actionFrames.size() * 6);
    double travel = 0;
    for (std::size_t a = 0; a < model_.actionCount(); ++a) {
      for (std::size_t t = 0; t < model_.actionLength(a); ++t) {
        const std::size_t k = model_.actionFrameBegin[a] + t;
        const GroundMotion at{model_.frameRoot[3 * k], model_.frameRoot[3 * k + 1], model_.frameRoot[3 * k + 2]};
        const Eigen::Vector3d pelvis = transformPoint(at, body_.point(model_.actionFrames[k], BodyTable::Pelvis));
        const Eigen::Vector3d head = transformPoint(at, body_.point(model_.actionFrames[k], BodyTable::Head));
        for (int d = 0; d < 3; ++d) {
          actionBody_[6 * k + static_cast<std::size_t>(d)] = static_cast<float>(pelvis[d]);
          actionBody_[6 * k + 3 + static_cast<std::size_t>(d)] = static_cast<float>(head[d]);
        }
        lean_ = std::max(lean_, std::hypot(head.x() - pelvis.x(), head.z() - pelvis.z()));
        if (t < aheadFrames_)
          travel = std::max({travel, std::hypot(pelvis.x(), pelvis.z()), std::hypot(head.x(), head.z())});
      }
    }
    reach_ = 2 * travel + 2 * p.bodyRadius + 0.05;
  }
  snapshot();
}

World::~World() = default;

void World::startAvatar(std::size_t i) {
  Avatar& a = avatars_[i];
  a.rng = Rng(mix(setup_.seed, i));
  const WorldParams& p = setup_.params;
  const bool sparring = p.mode == "sparring";
  const std::size_t n = avatars_.size();
  // Slots on a square grid: one per pair (sparring) or per avatar (targets).
  const std::size_t slot = sparring ? i / 2 : i;
  const std::size_t slots = sparring ? (n + 1) / 2 : n;
  const auto columns = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(slots))));
  const std::size_t rows = (slots + columns - 1) / columns;
  const double cx = (static_cast<double>(slot % columns) - 0.5 * static_cast<double>(columns - 1)) * p.spacing;
  const double cz = (static_cast<double>(slot / columns) - 0.5 * static_cast<double>(rows - 1)) * p.spacing;
  const bool paired = sparring && (i ^ 1) < n;
  a.partner = paired ? static_cast<std::int32_t>(i ^ 1) : -1;
  const double jitter = (2 * a.rng.uniform() - 1) * 20 * M_PI / 180;  // +-20 degrees
  if (paired) {
    const double side = (i % 2 == 0) ? -1 : 1;  // the even partner on the left, facing +X
    a.decision = {cx + side * 0.5 * p.startDistance, cz, -side * M_PI / 2 + jitter};
  } else {
    a.decision = {cx, cz, a.rng.uniform() * 2 * M_PI - M_PI};
  }
  a.now = a.decision;
  a.state = static_cast<std::uint32_t>(a.rng.below(model_.stateCount()));
  a.sourceFrame = model_.stateFrame[a.state];
  a.step = a.length = 0;  // decide at the first frame
  Target& t = targets_[i];
  if (!paired) {
    // A target in front, within reach of a few steps (the user's first placement).
    const double angle = (2 * a.rng.uniform() - 1) * M_PI / 3, distance = 0.8 + a.rng.uniform();
    placeTarget(t, a.decision, {distance * std::sin(angle), centroidHeight_, distance * std::cos(angle)}, a.rng, 0);
    t.nextMove = p.targetHold;
  }
  if (setup_.poses) {
    a.playback = std::make_unique<ActionPlayback>(*setup_.db, model_, setup_.blendFrames, false);
    a.playback->setFootLock(p.plantFeet);
    a.playback->setSourcePoses(sourcePoses_.get());
    a.playback->reset(a.state, a.decision);
    const std::size_t joints = setup_.db->skeleton->jointCount();
    a.pose.rotations.resize(joints);
    a.pose.translations.resize(joints);
  }
}

Eigen::Vector3d World::bodyPoint(std::size_t i, int which) const {
  const Avatar& a = avatars_[i];
  return transformPoint(a.now, body_.point(a.sourceFrame, which));
}

void World::placeTarget(Target& t, const GroundMotion& frame, const Eigen::Vector3d& local, Rng& rng, double time) {
  t.base = transformPoint(frame, local);
  if (!setup_.targetMotion) return;
  // Its motion drawn in the avatar frame, as the behaviours were trained and eval's trials
  // draw it, then turned into the world frame: a heading h in a frame of yaw y is h + y.
  t.path = setup_.targetMotion->draw(local, rng);
  t.path.position = t.base;
  t.path.heading += frame.dyaw;
  t.placedAt = time;
}

Eigen::Vector3d World::aim(std::size_t i) const {
  const Avatar& a = avatars_[i];
  return a.partner >= 0 ? heads_[static_cast<std::size_t>(a.partner)] : targets_[i].centre();
}

void World::recordAims() {
  for (std::size_t i = 0; i < avatars_.size(); ++i) {
    heads_[i] = bodyPoint(i, aimPoint_);
    roots_[i] = avatars_[i].now;
  }
}

Eigen::Vector3d World::seen(std::size_t i) const {
  const Avatar& a = avatars_[i];
  if (!setup_.opponent || a.partner < 0) return aim(i);
  // An opponent environment's state (opponent, learned_opponent) holds where the opponent
  // stands, its root on the ground, as training saw it; its head is only what the
  // strikes aim at. The head's height stays.
  const auto j = static_cast<std::size_t>(a.partner);
  return {roots_[j].dx, heads_[j].y(), roots_[j].dz};
}

void World::decide(std::size_t i, Controller& controller) {
  Avatar& a = avatars_[i];
  TargetState e = inverseTransformPoint(a.decision, seen(i));
  if (setup_.opponentPhases > 0) {
    // What the partner is doing, from the last frame's snapshot (the same whatever the
    // order avatars are advanced in): the state its action ends at and the frames left.
    if (a.partner >= 0) {
      const auto partner = static_cast<std::size_t>(a.partner);
      const Track& t = tracks_[partner];
      e.opponent = t.length > 0
                       ? opponentStateIndex(model_.actionTo[t.action], std::max<std::uint32_t>(1, t.length - t.step),
                                            t.length, setup_.opponentPhases)
                       : opponentStateIndex(avatars_[partner].state, 1, 1, setup_.opponentPhases);
    } else {
      e.opponent = 0;
    }
  }
  if (setup_.stances > 0) {
    if (a.stance < 0 || time() >= a.stanceUntil) {
      // The first uniformly; then one of the others, so that a hold is a stay in one stance.
      const auto n = static_cast<std::uint64_t>(setup_.stances);
      a.stance = a.stance < 0 || n == 1
                     ? static_cast<std::int32_t>(a.rng.below(n))
                     : static_cast<std::int32_t>((static_cast<std::uint64_t>(a.stance) + 1 + a.rng.below(n - 1)) % n);
      a.stanceUntil = time() - setup_.params.stanceHold * std::log1p(-a.rng.uniform());
    }
    e.stance = a.stance;
  }
  if (a.partner < 0 && targets_[i].path.moving()) {
    // A moving target: its motion now, seen from the decision's frame.
    const Target& t = targets_[i];
    e.speed = t.path.speed;
    e.heading = std::remainder(t.path.headingAt(time() - t.placedAt) - a.decision.dyaw, 2 * M_PI);
    e.turnRate = t.path.turnRate;
  }
  if (setup_.opponent)
    e.heading = a.partner >= 0
                    ? std::remainder(avatars_[static_cast<std::size_t>(a.partner)].now.dyaw - a.decision.dyaw, 2 * M_PI)
                    : std::atan2(-e.position.x(), -e.position.z());
  if (setup_.params.bodyRadius > 0) {
    thread_local std::vector<std::uint8_t> allowed;
    restrictActions(i, allowed);
    a.action = static_cast<std::uint32_t>(allowed.empty() ? controller.choose(a.state, e, a.rng)
                                                          : controller.choose(a.state, e, a.rng, allowed));
  } else {
    a.action = static_cast<std::uint32_t>(controller.choose(a.state, e, a.rng));
  }
  a.length = static_cast<std::uint32_t>(model_.actionLength(a.action));
  a.step = 0;
  a.hitCursor = model_.actionHitBegin[a.action];
  a.kickCursor = model_.actionKickBegin.empty() ? 0 : model_.actionKickBegin[a.action];
  ++a.decisions;
  a.decisionTarget = e;
  if (a.playback) a.playback->begin(a.action);
}

void World::advance(std::size_t begin, std::size_t end, unsigned worker) {
  Controller& controller = *controllers_[worker];
  Controller* partnerController = partnerControllers_.empty() ? nullptr : partnerControllers_[worker].get();
  const WorldParams& p = setup_.params;
  const double dt = model_.frameTime;
  const double time = static_cast<double>(frame_) * dt;  // frame_ already counts this frame
  const double omega = 2 * M_PI * p.bendFrequency;
  for (std::size_t i = begin; i < end; ++i) {
    Avatar& a = avatars_[i];
    if (a.partner < 0) {
      // The target: moved by "the user" now and then, and its spring relaxes.
      Target& t = targets_[i];
      if (time >= t.nextMove) {
        const double angle = (2 * a.rng.uniform() - 1) * M_PI, distance = 0.6 + 1.4 * a.rng.uniform();
        placeTarget(t, a.now, {distance * std::sin(angle), centroidHeight_, distance * std::cos(angle)}, a.rng, time);
        t.nextMove += p.targetHold;
      }
      if (t.path.moving()) t.base = t.path.at(time - t.placedAt);
      const Eigen::Vector3d acceleration = -omega * omega * t.bend - 2 * p.bendDamping * omega * t.bendVelocity;
      t.bendVelocity += dt * acceleration;
      t.bend += dt * t.bendVelocity;
      if (t.bend.norm() > p.bendMax) t.bend *= p.bendMax / t.bend.norm();
    }
    if (a.step == a.length) {
      if (a.length > 0) {  // the last action is over: decide where it ended
        a.decision = compose(a.decision, model_.displacement(a.action));
        a.state = model_.actionTo[a.action];
      }
      decide(i, partnerController && (i & 1) && a.partner >= 0 ? *partnerController : controller);
    }
    ++a.step;
    const std::size_t k = model_.actionFrameBegin[a.action] + a.step - 1;
    a.sourceFrame = model_.actionFrames[k];
    a.now = compose(a.decision, {model_.frameRoot[3 * k], model_.frameRoot[3 * k + 1], model_.frameRoot[3 * k + 2]});
  }
}

void World::updatePoses(std::size_t begin, std::size_t end) {
  const Skeleton& skeleton = *setup_.db->skeleton;
  const double time = static_cast<double>(frame_) * model_.frameTime;
  const double tau = setup_.params.reactionSeconds / 5;  // 5 tau: under 10 % left
  for (std::size_t i = begin; i < end; ++i) {
    Avatar& a = avatars_[i];
    a.playback->next(a.pose);
    const double t = time - a.reactionStart;
    if (t > 0 && t < 10 * tau) {
      // Hit reaction (paper sec. 6.6): move the struck point by d(t) = push (t/tau) e^(1 - t/tau),
      // rising smoothly to `push` at tau and fading, by rotating the joints above it in the
      // spine chain (rotations only, so bone lengths never change).
      const double shape = (t / tau) * std::exp(1 - t / tau);
      const Eigen::Vector3d d = shape * a.push;
      const ReactionChain& chain = reactionChains_[static_cast<std::size_t>(a.part)];
      const double share = chain.joints.empty() ? 0 : 1.0 / static_cast<double>(chain.joints.size());
      // The playback's kinematics of this frame, deformed in place.
      const std::span<Eigen::Vector3d> positions = a.playback->positions();
      const std::span<Eigen::Quaterniond> globals = a.playback->globalRotations();
      const auto target = static_cast<std::size_t>(chain.struck);
      for (std::size_t c = 0; c < chain.joints.size(); ++c) {  // from the lowest joint up
        const auto joint = static_cast<std::size_t>(chain.joints[c]);
        const Eigen::Vector3d from = positions[target] - positions[joint];
        const Eigen::Vector3d to = from + share * d;
        if (from.norm() < 1e-6) continue;
        const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(from, to);
        const int parent = skeleton.joint(joint).parent;
        const Eigen::Quaterniond parentGlobal =
            parent >= 0 ? globals[static_cast<std::size_t>(parent)] : Eigen::Quaterniond::Identity();
        a.pose.rotations[joint] = (parentGlobal.conjugate() * turn * globals[joint]).normalized();
        // Only the turned joint and those below it move: their pass of the kinematics.
        forwardKinematicsOf(skeleton, chain.below[c], a.pose.rotations, a.pose.translations, globals, positions);
      }
    }
    if (setup_.record) a.recorded.push_back(a.pose);
  }
}

void World::setControllerFactory(std::function<std::unique_ptr<Controller>()> makeController) {
  if (!makeController) throw Error("world: expected a controller factory");
  setup_.makeController = std::move(makeController);
  controllers_.clear();  // run() makes as many as it needs
}

void World::run(std::size_t frames) {
  const std::size_t n = avatars_.size();
  // Threads pay off only with many avatars (three barriers per frame).
  const auto threads = static_cast<unsigned>(
      std::clamp<std::size_t>(std::min<std::size_t>(setup_.threads, n / 64), 1, 64));
  while (controllers_.size() < threads) controllers_.push_back(setup_.makeController());
  if (setup_.makePartnerController)
    while (partnerControllers_.size() < threads) partnerControllers_.push_back(setup_.makePartnerController());
  std::vector<std::vector<HitEvent>> found(threads);
  auto range = [&](unsigned w) { return std::pair<std::size_t, std::size_t>{n * w / threads, n * (w + 1) / threads}; };
  auto finishFrame = [&] {
    // Events in avatar order whatever the thread count; reactions after every check, so
    // that no collision sees another's reaction within the frame.
    for (auto& list : found) {
      for (const HitEvent& e : list) {
        events_.push_back(e);
        blocked_ += e.blocked ? 1 : 0;
        react(e);
      }
      list.clear();
    }
    recordAims();
  };
  // Where the avatars now are, for the next decisions; bodies that overlap are pushed apart
  // before anything is posed or collides.
  auto placeBodies = [&] {
    snapshot();
    if (setup_.params.bodyRadius > 0) separate();
  };
  if (threads == 1) {
    for (std::size_t f = 0; f < frames; ++f) {
      ++frame_;
      advance(0, n, 0);
      placeBodies();
      if (setup_.poses) updatePoses(0, n);
      collide(0, n, found[0]);
      finishFrame();
    }
    return;
  }
  std::exception_ptr failure;
  std::mutex failureMutex;
  std::barrier sync(static_cast<std::ptrdiff_t>(threads));
  auto work = [&](unsigned w) {
    const auto [begin, end] = range(w);
    for (std::size_t f = 0; f < frames; ++f) {
      if (w == 0) ++frame_;
      sync.arrive_and_wait();
      try {
        advance(begin, end, w);
      } catch (...) {
        const std::lock_guard lock(failureMutex);
        if (!failure) failure = std::current_exception();
      }
      sync.arrive_and_wait();
      if (w == 0) placeBodies();
      sync.arrive_and_wait();
      if (setup_.poses) updatePoses(begin, end);
      collide(begin, end, found[w]);
      sync.arrive_and_wait();
      if (w == 0) finishFrame();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 1; w < threads; ++w) pool.emplace_back(work, w);
  work(0);
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

std::size_t World::decisions() const {
  std::size_t total = 0;
  for (const Avatar& a : avatars_) total += a.decisions;
  return total;
}

void World::moveTarget(std::size_t i, const Eigen::Vector3d& base) {
  if (i >= avatars_.size() || avatars_[i].partner >= 0)
    throw Error(fmt::format("world: expected an avatar with a target of its own, found avatar {}", i));
  targets_[i].base = base;
  targets_[i].path = TargetState();  // the user's target stands where it is put
  targets_[i].nextMove = std::numeric_limits<double>::infinity();
}


World::BodyStats World::bodyStats() const {
  BodyStats stats;
  for (const auto& c : bodyCounts_) {
    stats.restricted += c[0];
    stats.cornered += c[1];
  }
  stats.pushes = pushes_;
  return stats;
}

std::size_t World::avatarCount() const { return avatars_.size(); }
GroundMotion World::avatarFrame(std::size_t i) const { return avatars_[i].now; }
World::Decision World::lastDecision(std::size_t i) const {
  const Avatar& a = avatars_[i];
  return {a.state, a.action, a.decision, a.decisionTarget, a.decisions};
}
int World::partner(std::size_t i) const { return avatars_[i].partner; }
const Target& World::target(std::size_t i) const { return targets_[i]; }
const Pose& World::pose(std::size_t i) const { return avatars_[i].pose; }
std::span<const Eigen::Vector3d> World::jointPositions(std::size_t i) const {
  const Avatar& a = avatars_[i];
  return a.playback ? std::as_const(*a.playback).positions() : std::span<const Eigen::Vector3d>();
}
const std::vector<Pose>& World::recorded(std::size_t i) const { return avatars_[i].recorded; }

std::size_t World::bytesPerAvatar() const {
  std::size_t bytes = sizeof(Avatar) + sizeof(Target) + sizeof(Eigen::Vector3d) + sizeof(Track) + sizeof(Eigen::Vector2d) +
                      sizeof(std::array<std::size_t, 2>) + sizeof(std::int64_t) + 3 * sizeof(std::uint32_t);
  if (setup_.poses) {
    const std::size_t joints = setup_.db->skeleton->jointCount();
    // The playback's buffers (4 rotation arrays: the shown and expected poses, the blend
    // offsets, the global rotations; the positions; the offsets' half angles and axes) and
    // the avatar's pose. The source poses are shared by all avatars.
    bytes += sizeof(ActionPlayback) +
             joints * (4 * sizeof(Eigen::Quaterniond) + 2 * sizeof(Eigen::Vector3d) + sizeof(double));
    bytes += joints * (sizeof(Eigen::Quaterniond) + sizeof(Eigen::Vector3d));
  }
  return bytes;
}

}  // namespace mgrl
