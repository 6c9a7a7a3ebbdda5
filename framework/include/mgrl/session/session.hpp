#pragma once
/// \file
/// One way into the pipeline (DESIGN.md sec. 2): a Session is a scenario opened with its
/// graph, behaviours, the task they share and, when asked for, the policy bundle bound to
/// them. `mgrl eval`, `simulate`, `serve`, the benchmarks and the Python module open one
/// and go from it, instead of composing the chain scenario -> graph -> behaviours ->
/// policy -> controllers -> world each on its own.
///
///   mgrl::SessionOptions options;
///   options.scenario = "scenarios/boxing.yaml";
///   auto session = mgrl::openSession(options, {.policy = mgrl::PolicyNeed::Required});
///   mgrl::World world(session->worldSetup(2, 1, {.name = "policy"}));
///   world.run(300);
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/controllers.hpp"
#include "mgrl/session/graph_source.hpp"
#include "mgrl/session/plugins.hpp"
#include "mgrl/session/policy_source.hpp"
#include "mgrl/session/task.hpp"

namespace mgrl {

enum class PolicyNeed {
  None,         ///< no bundle is read (training, the online search, random actions)
  Required,     ///< a bundle must serve: a missing or stale one is an error
  IfAvailable,  ///< the bundle is used when it serves; else Session::policyNote says why not
};

/// What a caller needs from the session beyond the scenario itself.
struct SessionNeeds {
  PolicyNeed policy = PolicyNeed::None;
  /// The bundle to use; "" the scenario's default one (defaultPolicyDirectory()).
  std::filesystem::path policyDir = {};
  /// Parse the capture even when the graph comes from the cache: poses, bodies and BVH
  /// need it; trials and training need only the model (a cached graph then starts faster).
  bool motion = true;
  /// Called with the final scenario after every check that needs no graph and before the
  /// graph is loaded (a command's own checks, so that their message is the only one).
  std::function<void(const Scenario&)> beforeGraph = nullptr;
  /// A graph another session already holds: copied instead of loaded when it was made from
  /// the same capture and graph parameters (equal keys) and has what `motion` asks for (the
  /// viewer's sparring scenario on the paper's boxer's capture). Null: loaded as usual.
  const GraphResult* graphFrom = nullptr;
};

/// The tables a run plays, as a value passed to the world's set-up, evaluate and simulate
/// (the session stays as it was opened): the main ones for every avatar and, in sparring, a
/// partner's for the second avatar of each pair.
struct Policies {
  Policies() = default;
  /// The caller's own tables for every avatar (tables that outlive the world, e.g. Python's).
  explicit Policies(std::vector<PolicyPart> parts) : main(std::move(parts)) {}

  std::vector<PolicyPart> main;      ///< one per behaviour, in order (empty: no tables)
  std::vector<PolicyPart> partner;   ///< empty: the second avatar plays `main`, or the scripted opponent
  std::filesystem::path dir;         ///< the bundle `main` comes from ("": the caller's own tables)
  std::filesystem::path partnerDir;  ///< the bundle `partner` comes from
  /// Bundles read for this value that the parts point into (a self-play round's, a
  /// partner's); the session's own bundle belongs to the session.
  std::shared_ptr<const PolicyBundle> mainBundle, partnerBundle;
};

/// An opened scenario. openSession() returns it const: nothing changes it once opened; what
/// varies from run to run (the tables played) is a Policies value.
class Session {
 public:
  explicit Session(Scenario checked) : scenario(std::move(checked)) {}
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  SessionOptions options;
  Scenario scenario;  ///< checked; with a bundle's own settings if one was adopted
  GraphResult graph;
  std::vector<Behavior> behaviors;  ///< the scenario's, in its order
  Task task;                        ///< what they share, checked once
  /// The policy bundle and one part per behaviour pointing into it (empty: none read).
  std::filesystem::path policyDir;
  PolicyBundle bundle;
  std::vector<PolicyPart> policy;
  /// PolicyNeed::IfAvailable and no bundle used: why (shown to the user); "" otherwise.
  std::string policyNote;
  /// The behaviours as the online search sees them (rewards, weights, activations).
  std::vector<SearchPart> search;
  /// The avatars' body capsules (empty without the capture: SessionNeeds::motion false).
  BodyTable body;

  const StateActionModel& model() const { return graph.model; }
  /// The registries the session was opened with (SessionOptions::plugins): the behaviours'
  /// plug-ins and the controllers its worlds, eval and simulate choose from.
  const Plugins& plugins() const { return *options.plugins; }
  /// True when the capture was parsed (SessionNeeds::motion): poses, bodies and exports.
  bool hasMotion() const { return graph.db.skeleton != nullptr; }
  /// What makeController() needs; `variety` is the policy's choice among near-best actions
  /// ({}: greedy, as eval measures; task.world.variety: as the world plays).
  ControllerParts controllerParts(Variety variety = {}) const;

  /// The bundle the session opened with: `policy`, from `policyDir`.
  Policies policies() const;
  /// Self-play round `round`'s tables (NAME-roundK, kept by mgrl train) of the session's
  /// bundle instead of its final ones, read again from `policyDir`, so that any two rounds
  /// can spar. Throws mgrl::Error without a bundle, or naming the bundle and what it has
  /// when a behaviour lacks that round.
  Policies roundPolicies(int round) const;
  /// `played` with the second avatar of each sparring pair playing `dir`, a bundle trained
  /// on this graph with tables for every behaviour (checked as the main one is; `round` > 0:
  /// that self-play round's tables). Throws mgrl::Error naming the bundle's problem.
  Policies withPartner(Policies played, const std::filesystem::path& dir, int round = 0) const;
  /// Refuses a self-play round without a partner bundle, before anything loads: mgrl::Error
  /// naming the two settings as the caller calls them (the command line's by default).
  static void checkPartnerChoice(const std::filesystem::path& dir, int round,
                                 std::string_view roundName = "--partner-round",
                                 std::string_view dirName = "--partner-policy DIR");

  /// A world of `avatars` on this session's graph and task (mode, spacing ... from
  /// `world:`), each avatar run by a controller of `choice` (a name in plugins().controllers)
  /// with the world's variety (`topK` > 0: choosing among that many near-best actions
  /// instead). One thread, no poses: set WorldSetup::threads, poses and record as needed. In sparring, the second
  /// avatar of each pair plays `played.partner` if it has tables, else the scenario's scripted opponent if it has one
  /// (partnerName()), else `choice` too.
  WorldSetup worldSetup(std::size_t avatars, std::uint64_t seed, const ControllerChoice& choice, const Policies& played,
                        int topK = 0) const;
  /// The same with the session's bundle.
  WorldSetup worldSetup(std::size_t avatars, std::uint64_t seed, const ControllerChoice& choice) const {
    return worldSetup(avatars, seed, choice, policies());
  }
  /// The same, the policy controllers playing `parts` (tables that outlive the world, e.g.
  /// Python's) instead of the session's bundle.
  WorldSetup worldSetup(std::size_t avatars, std::uint64_t seed, const ControllerChoice& choice,
                        const std::vector<PolicyPart>& parts) const {
    return worldSetup(avatars, seed, choice, Policies(parts));
  }
  /// What the second avatar of a sparring pair plays, for reports and the viewer: "" (the
  /// same as the first), "partner_policy" or "pursue" / "stand" (the scripted opponent).
  std::string partnerName(const Policies& played) const;
  /// The same with the session's bundle (no partner's): "" or the scripted opponent.
  std::string partnerName() const { return partnerName(Policies{}); }
};

/// Opens the scenario of `options` for `needs`: the scenario checked, the bundle looked up
/// (and checked from its manifest) before the graph is loaded, the graph from the cache or
/// built, the behaviours built, the task checked, the bundle's tables bound. Throws
/// mgrl::Error (ConfigError with file:line:col for the scenario's mistakes).
std::unique_ptr<const Session> openSession(const SessionOptions& options, const SessionNeeds& needs = {});

/// A hit as the events file and the viewer's protocol carry it: {"time", "attacker",
/// "target", "part" (head, chest, spine, or target; left_arm or right_arm when blocked),
/// "hand", "limb", "speed", "blocked", "point"}.
nlohmann::json hitEventJson(const HitEvent& event);

}  // namespace mgrl
