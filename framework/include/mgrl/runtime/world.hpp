#pragma once
/// \file
/// The runtime world (paper sec. 5, 6.6): avatars playing actions chosen by a controller,
/// targets (static, moved by a user, or another avatar's head), collisions checked only at
/// effective-punch frames, and reactions (a hit target bends and springs back; a hit
/// avatar's struck body part gives way through a small inverse-kinematics adjustment).
///
/// Avatars move exactly by the model's ground motions (what the learners assumed), so the
/// control-and-collision loop needs no joint angles: the upper body and the fists come
/// from per-frame tables. Poses (blending, forward kinematics of every joint, reactions)
/// are computed only when asked for, from the same avatar states, so asking for them never
/// changes what happens.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "mgrl/core/config.hpp"
#include "mgrl/core/params.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/graph/playback.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "mgrl/learning/environment_model.hpp"
#include "mgrl/learning/target_state.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/runtime/controller.hpp"

namespace mgrl {

/// The scenario's `world:` section (scenarios/README.md), validated by worldParamSpecs().
struct WorldParams {
  /// sparring: avatars in pairs, each using the other's head as its target (an odd one
  /// out gets a target); targets: every avatar has its own target, moved to a new place
  /// every `target_hold` seconds (a stand-in for the user's mouse).
  std::string mode = "sparring";
  Variety variety{3, 0.1};
  double spacing = 4.0;        ///< m between the centres of neighbouring pairs
  double startDistance = 1.6;  ///< m between sparring partners at the start
  double targetHold = 3.0;     ///< s a target stays before it is moved (targets mode)
  double stanceHold = 0.8;     ///< s, mean time a fighter holds a stance (WorldSetup::stances)
  double targetHeight = -1;    ///< m; < 0: the effective hitting points' centroid height
  double targetRadius = 0.12;  ///< m, target sphere
  double fistRadius = 0.05;    ///< m, fist sphere
  double footRadius = 0.06;    ///< m, toe sphere (kicks)
  /// sparring: the point of the partner each avatar aims at, "head" or "chest".
  std::string aim = "head";
  double headRadius = 0.11, chestRadius = 0.16, spineRadius = 0.14;  ///< m, body capsules
  /// Each forearm and glove is a capsule from the elbow to the fist tip of this radius: a
  /// strike whose fist or toe meets the partner's before it reaches the head or body is
  /// blocked. 0: nothing blocks, every strike that reaches the body lands.
  double guardRadius = 0.06;  ///< m
  /// Bodies collide: each avatar's torso is a capsule from the pelvis to the head of this
  /// radius; a decision rules out actions whose root path would bring it into another's
  /// within `avoidSeconds`, and overlaps left are pushed apart at `separationSpeed`.
  /// 0: bodies pass through each other (the paper's world).
  double bodyRadius = 0.2;          ///< m
  double avoidSeconds = 1.0;        ///< s
  double separationSpeed = 1.5;     ///< m/s
  bool plantFeet = true;            ///< poses: planted feet held by IK (ActionPlayback::setFootLock)
  double bendPerSpeed = 0.03;       ///< m of target bend per m/s of fist speed
  double bendMax = 0.35;            ///< m
  double bendFrequency = 1.5;       ///< Hz, the target's spring
  double bendDamping = 0.25;        ///< damping ratio of the target's spring
  double reactionPerSpeed = 0.012;  ///< m of body-part displacement per m/s of fist speed
  double reactionMax = 0.08;        ///< m
  double reactionSeconds = 0.5;     ///< s until a reaction has (all but) faded
};

/// The parameters of `world:`, for validation and `mgrl list`.
const ParamSpecs& worldParamSpecs();
/// Reads a `world:` block (absent: defaults). Throws ConfigError.
WorldParams readWorldParams(const ConfigNode& node);
/// The block as JSON (for reports).
nlohmann::json worldParamsJson(const WorldParams& params);

/// Body parts the opponent's fists collide with (paper sec. 6.6), as capsules, and the arms
/// that block them (a strike meeting a forearm or glove first is blocked).
enum class BodyPart : std::uint8_t { Spine = 0, Chest = 1, Head = 2, LeftArm = 3, RightArm = 4 };
inline constexpr std::size_t kBodyParts = 5;
const char* bodyPartName(BodyPart part);

/// Per source frame, the upper-body points of the capsules in that frame's avatar frame:
/// pelvis, chest, neck, head, head top, and each forearm's elbow and fist tip (float, 27
/// per frame). Built once from the capture.
struct BodyTable {
  static constexpr int kPoints = 9;
  enum Point {
    Pelvis = 0,
    Chest = 1,
    Neck = 2,
    Head = 3,
    HeadTop = 4,
    LeftElbow = 5,
    LeftFist = 6,
    RightElbow = 7,
    RightFist = 8
  };
  std::vector<float> points;  ///< frameCount * kPoints * 3
  /// Joints of the chain used by reactions: the chest and neck joints found from the head
  /// up to the pelvis.
  int chestJoint = -1, neckJoint = -1, headJoint = -1, pelvisJoint = -1;
  /// Per side, the fist joint and the arm joints above it that a blocked strike turns
  /// (shoulder side first): the reaction chain of BodyPart::LeftArm and RightArm.
  std::array<int, 2> fistJoint{-1, -1};
  std::array<std::vector<int>, 2> armJoints;

  Eigen::Vector3d point(std::uint32_t frame, int which) const {
    const float* p = points.data() + (static_cast<std::size_t>(frame) * kPoints + which) * 3;
    return {p[0], p[1], p[2]};
  }
};

/// Finds the chest and neck on the path from the head to the pelvis and tabulates the
/// points. Throws mgrl::Error if the head is not below the pelvis in the hierarchy.
BodyTable makeBodyTable(const MotionDatabase& db);

/// One landed punch or kick, or one blocked: it met a forearm or glove of the opponent
/// before reaching the head or body (`blocked`, `part` the arm).
struct HitEvent {
  double time = 0;                                  ///< s since the start
  std::uint32_t attacker = 0;                       ///< avatar index
  std::int32_t target = -1;                         ///< avatar index, or -1 for the attacker's own target
  std::uint8_t hand = 0;                            ///< 0 left, 1 right (the foot, for a kick)
  bool kick = false;                                ///< a toe's effective kick, not a fist's punch
  BodyPart part = BodyPart::Head;                   ///< what was struck (Head for a target; an arm when blocked)
  bool blocked = false;                             ///< met the opponent's guard: not a landed hit
  double speed = 0;                                 ///< fist speed, m/s
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< fist tip, world (m)
};

/// A target sphere on a springy stand: base position plus a bend that a hit excites and a
/// damped spring pulls back.
struct Target {
  Eigen::Vector3d base = Eigen::Vector3d::Zero();
  Eigen::Vector3d bend = Eigen::Vector3d::Zero(), bendVelocity = Eigen::Vector3d::Zero();
  double nextMove = 0;  ///< s, targets mode
  /// How the base moves (WorldSetup::targetMotion), in the world frame from where it was
  /// placed at `placedAt` s: base = path.at(time - placedAt). Speed 0: it stands.
  TargetState path;
  double placedAt = 0;
  Eigen::Vector3d centre() const { return base + bend; }
};

struct WorldSetup {
  const StateActionModel* model = nullptr;
  const BodyTable* body = nullptr;
  /// Required for poses (forward kinematics, BVH); may be null otherwise.
  const MotionDatabase* db = nullptr;
  int blendFrames = 6;
  WorldParams params;
  /// Makes one controller per worker thread.
  std::function<std::unique_ptr<Controller>()> makeController;
  std::size_t avatars = 2;
  std::uint64_t seed = 1;
  unsigned threads = 1;
  /// Compute every joint's pose each frame (blending, forward kinematics, reactions).
  bool poses = false;
  /// Keep every avatar's poses for export (implies poses).
  bool record = false;
  /// The behaviours' environment is an `opponent`: controllers also see which
  /// way the target faces (TargetState::heading): a partner's own facing (sparring), or,
  /// for a target of the targets mode, straight at the avatar (an opponent that turns to
  /// face it, as the model's does).
  bool opponent = false;
  /// The behaviours' environment is a `learned_opponent` with this many phases per
  /// graph state: controllers also see what a sparring partner is doing (TargetState::
  /// opponent: the state its action ends at and the phase of the frames left, as the tables
  /// were trained with); a target of the targets mode is taken to be about to arrive at
  /// state 0. 0: no such state.
  int opponentPhases = 0;
  /// The behaviours' environment moves its targets (a `moving_target`, TargetMotion::maxSpeed > 0):
  /// each time a target of the targets mode is placed, its motion (speed, direction, turn
  /// rate) is drawn from this model as eval's trials draw it, the target then moves along
  /// it, and controllers see that motion (TargetState::speed, heading, turnRate). A target
  /// the user moves (moveTarget) stands. Sparring's odd one out has such a target too.
  /// Null: targets stand (the paper's). It must outlive the world.
  const EnvironmentModel* targetMotion = nullptr;
  /// Stances the behaviours number (`stance: k`): each avatar draws one uniformly,
  /// holds it for an exponential time of mean params.stanceHold, then changes to one of the
  /// others, drawn uniformly (at its next decision); controllers see it as
  /// TargetState::stance. 0: no stances.
  int stances = 0;
  /// Optional: makes the controllers of the second avatar of each sparring pair (odd
  /// indices), so that two policies spar (`simulate --partner-policy`); unset, every avatar
  /// plays makeController's.
  std::function<std::unique_ptr<Controller>()> makePartnerController;
  /// Optional: `db`'s source poses (makeSourcePoses()), made once and shared by the worlds
  /// that pose a crowd from the same capture (the viewer's pages). Null: a world of many
  /// avatars with poses makes its own (a forward-kinematics pass over every frame).
  std::shared_ptr<const SourcePoses> sourcePoses;
};

class World {
 public:
  /// Places the avatars (pairs on a square grid, partners facing each other) at random
  /// states drawn from the seed. Throws mgrl::Error on an impossible setup.
  explicit World(WorldSetup setup);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// Simulates `frames` more frames (one model frame each). Deterministic for a seed,
  /// whatever the thread count.
  void run(std::size_t frames);
  /// Replaces the controllers (a live switch in the viewer: another controller, other
  /// weights); the avatars carry on from where they are, deciding with the new ones from
  /// their next decision.
  void setControllerFactory(std::function<std::unique_ptr<Controller>()> makeController);

  std::size_t avatarCount() const;
  /// The `world:` settings it runs with (WorldSetup::params).
  const WorldParams& params() const { return setup_.params; }
  std::size_t frame() const { return frame_; }
  double time() const { return static_cast<double>(frame_) * model_.frameTime; }
  /// Landed and blocked strikes in the order they happened (HitEvent::blocked).
  const std::vector<HitEvent>& events() const { return events_; }
  /// How many of events() landed (the rest were blocked).
  std::size_t landedCount() const { return events_.size() - blocked_; }
  std::size_t blockedCount() const { return blocked_; }
  std::size_t decisions() const;
  /// The avatar frame (ground position and facing) of avatar i now, in the world.
  GroundMotion avatarFrame(std::size_t i) const;
  /// Avatar i's last decision: the state it decided at, the action it took and its avatar
  /// frame then (world). For views that show what the controller saw.
  struct Decision {
    std::uint32_t state = 0, action = 0;
    GroundMotion frame;
    TargetState target;     ///< the environment state in that frame (aim point, and its motion or facing), as the
                            ///< controller saw it
    std::size_t count = 0;  ///< avatar i's decisions so far (this one included)
  };
  Decision lastDecision(std::size_t i) const;
  /// The point avatar i aims at now (its partner's head or its target's centre).
  Eigen::Vector3d aim(std::size_t i) const;
  /// Where avatar i's controller sees its target now (the position of TargetState): the aim
  /// point, or in a scene of opponent environments (WorldSetup::opponent) its partner's root
  /// on the ground at the head's height, as those environments' states hold it.
  Eigen::Vector3d seen(std::size_t i) const;
  /// Avatar i's partner, or -1 if it has a target of its own.
  int partner(std::size_t i) const;
  const Target& target(std::size_t i) const;
  /// The user drags avatar i's target (one without a partner) to `base` (world); automatic
  /// moves stop for it. Throws mgrl::Error for an avatar with a partner.
  void moveTarget(std::size_t i, const Eigen::Vector3d& base);
  /// Avatar i's current pose (world), when poses are on.
  const Pose& pose(std::size_t i) const;
  /// World joint positions of avatar i's current pose, when poses are on.
  std::span<const Eigen::Vector3d> jointPositions(std::size_t i) const;
  /// Every recorded pose of avatar i (one per simulated frame), when recording.
  const std::vector<Pose>& recorded(std::size_t i) const;
  /// Bytes of per-avatar state (excluding recordings), for the memory report.
  std::size_t bytesPerAvatar() const;
  /// Avatar i's pelvis and head (world) now: the ends of its torso capsule.
  Eigen::Vector3d pelvis(std::size_t i) const { return bodyPoint(i, BodyTable::Pelvis); }
  Eigen::Vector3d head(std::size_t i) const { return bodyPoint(i, BodyTable::Head); }
  /// Body collisions so far: decisions at which some actions were ruled out, decisions at
  /// which every action ran into a body (the one keeping the most room was taken), and
  /// frames at which an overlap was pushed apart (one per pair).
  struct BodyStats {
    std::size_t restricted = 0, cornered = 0, pushes = 0;
  };
  BodyStats bodyStats() const;

 private:
  struct Avatar;
  struct Worker;
  void startAvatar(std::size_t i);
  void decide(std::size_t i, Controller& controller);
  /// Puts target t at `local` in `frame` (at `time` s) and, with a targetMotion, draws how it moves.
  void placeTarget(Target& t, const GroundMotion& frame, const Eigen::Vector3d& local, Rng& rng, double time);
  void advance(std::size_t begin, std::size_t end, unsigned worker);
  void collide(std::size_t begin, std::size_t end, std::vector<HitEvent>& out);
  void react(const HitEvent& event);
  void updatePoses(std::size_t begin, std::size_t end);
  Eigen::Vector3d bodyPoint(std::size_t i, int which) const;
  // Body collisions (WorldParams::bodyRadius).
  struct Track;
  struct Segment {
    Eigen::Vector3d pelvis, head;
  };
  Segment predict(std::size_t j, std::uint32_t ahead) const;
  Segment place(const GroundMotion& at, double c, double s, std::size_t k) const;
  void snapshot();
  /// heads_ and roots_ from where every avatar is now (the decisions' view of the last frame).
  void recordAims();
  void buildGrid();
  template <class F>
  void forNeighbours(const Eigen::Vector3d& at, F&& visit) const;
  void separate();
  void restrictActions(std::size_t i, std::vector<std::uint8_t>& allowed);

  WorldSetup setup_;
  const StateActionModel& model_;
  const BodyTable& body_;
  std::shared_ptr<const SourcePoses> sourcePoses_;  ///< with poses: shared by every avatar's playback
  /// Per struck BodyPart, the joints a hit reaction turns (lowest first) and, for each, the
  /// joints its turn moves (subtreeJoints()).
  struct ReactionChain {
    int struck = 0;
    std::vector<int> joints;
    std::vector<std::vector<int>> below;
  };
  std::array<ReactionChain, kBodyParts> reactionChains_;
  std::vector<Avatar> avatars_;
  std::vector<Target> targets_;
  std::vector<Eigen::Vector3d> heads_;  ///< every avatar's aim point (head or chest) at the end of the last frame
  /// Every avatar's root on the ground at the end of the last frame: where an opponent
  /// stands, as the opponent environments' states hold it.
  std::vector<GroundMotion> roots_;
  std::vector<HitEvent> events_;
  std::size_t blocked_ = 0;  ///< events_ with `blocked`
  std::vector<std::unique_ptr<Controller>> controllers_;
  std::vector<std::unique_ptr<Controller>> partnerControllers_;  ///< one per worker, if makePartnerController
  std::size_t frame_ = 0;
  double centroidHeight_ = 0;
  int aimPoint_ = BodyTable::Head;
  // Body collisions: every avatar as the last frame left it (read while avatars move), a
  // hashed grid of their pelvises, pushes to apply at their next frame.
  std::vector<Track> tracks_;
  double reach_ = 0;               ///< m: bodies farther apart cannot meet within the look-ahead
  double lean_ = 0;                ///< m: the farthest a head gets from its pelvis on the floor
  std::vector<float> actionBody_;  ///< per action frame: pelvis and head in the action's starting avatar frame
  std::uint32_t aheadFrames_ = 0;
  std::vector<std::uint32_t> gridStart_, gridItems_;
  std::vector<std::int64_t> gridCell_;  ///< per avatar: its cell (x, z) packed
  std::vector<Eigen::Vector2d> pending_;
  std::vector<std::array<std::size_t, 2>> bodyCounts_;  ///< per avatar: restricted, cornered
  std::size_t pushes_ = 0;
};

}  // namespace mgrl
