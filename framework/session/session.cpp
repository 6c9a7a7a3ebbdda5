#include "mgrl/session/session.hpp"

#include <map>
#include <vector>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/motion_database.hpp"
#include "mgrl/scenario/behaviors.hpp"

namespace mgrl {

ControllerParts Session::controllerParts(Variety variety) const {
  ControllerParts parts;
  parts.model = &graph.model;
  parts.policy = policy;
  parts.search = search;
  parts.environment = task.environment;
  parts.gamma = task.gamma;
  parts.variety = variety;
  return parts;
}

Policies Session::policies() const {
  Policies played(policy);
  played.dir = policyDir;
  return played;
}

WorldSetup Session::worldSetup(std::size_t avatars, std::uint64_t seed, const ControllerChoice& choice,
                               const Policies& played, int topK) const {
  const ControllerRegistry& controllers = plugins().controllers;
  checkControllerChoice(controllers, choice);
  WorldSetup setup;
  setup.model = &graph.model;
  setup.body = &body;
  setup.db = &graph.db;
  setup.blendFrames = scenario.graph.blendFrames;
  setup.params = task.world;
  setup.avatars = avatars;
  setup.seed = seed;
  setup.opponent = task.opponent;
  setup.opponentPhases = task.opponentPhases;
  if (task.targetMotion && task.targetMotion->maxSpeed > 0) setup.targetMotion = task.environment;
  setup.stances = stanceCount(behaviors);
  Variety variety = task.world.variety;
  if (topK > 0) variety.topK = topK;
  setup.params.variety = variety;
  ControllerParts parts = controllerParts(variety);
  parts.policy = played.main;
  requireParts(controllers, choice, parts);  // now, not at the world's first decision
  // By reference, as the parts hold the model: the caller's registries (SessionOptions::
  // plugins) outlive the session and so its worlds.
  setup.makeController = [&controllers, choice, parts] { return makeController(controllers, choice, parts); };
  if (!played.partner.empty()) {
    ControllerParts partner = parts;
    partner.policy = played.partner;
    const ControllerChoice greedy{.name = "policy"};
    setup.makePartnerController = [&controllers, greedy, partner] {
      return makeController(controllers, greedy, partner);
    };
  } else if (task.scriptedOpponent) {
    // An `opponent` scene (dodge): the partner is the opponent the tables were trained
    // against, played with graph actions, so that it is a body that moves and strikes.
    const StateActionModel* model = &graph.model;
    const Task::ScriptedOpponent o = *task.scriptedOpponent;
    setup.makePartnerController = [model, o] {
      return std::make_unique<PursueController>(*model, o.stopDistance, o.stand);
    };
  }
  return setup;
}

std::string Session::partnerName(const Policies& played) const {
  if (!played.partner.empty()) return "partner_policy";
  if (task.scriptedOpponent) return task.scriptedOpponent->stand ? "stand" : "pursue";
  return "";
}

void Session::checkPartnerChoice(const std::filesystem::path& dir, int round, std::string_view roundName,
                                 std::string_view dirName) {
  if (round > 0 && dir.empty())
    throw Error(fmt::format("{}: expected {} as well (the bundle whose round the partner plays)", roundName, dirName));
}

namespace {

// Self-play rounds are kept as NAME-roundK (mgrl train): each behaviour's table
// is replaced by its round's, which leaves the bundle. Every round's table is found before
// any is taken, so a missing one leaves the bundle as it was.
void takeRound(PolicyBundle& bundle, const std::filesystem::path& dir, const std::vector<Behavior>& behaviors,
               int round) {
  std::vector<std::map<std::string, PolicyBehavior>::iterator> rounds;
  for (const Behavior& b : behaviors) {
    const std::string name = fmt::format("{}-round{}", b.name, round);
    const auto found = bundle.behaviors.find(name);
    if (found == bundle.behaviors.end()) {
      std::string have;
      for (const auto& entry : bundle.behaviors) have += (have.empty() ? "" : ", ") + entry.first;
      throw Error(fmt::format("{}: expected self-play round {}'s table for behaviour '{}' ({}), found only {}",
                              dir.string(), round, b.name, name, have));
    }
    rounds.push_back(found);
  }
  for (std::size_t i = 0; i < behaviors.size(); ++i) {
    bundle.behaviors[behaviors[i].name] = std::move(rounds[i]->second);
    bundle.behaviors.erase(rounds[i]);
  }
}

}  // namespace

Policies Session::roundPolicies(int round) const {
  if (policyDir.empty()) throw Error(fmt::format("self-play round {}: expected a policy bundle, found none", round));
  auto roundBundle = std::make_shared<PolicyBundle>(loadPolicyBundle(policyDir, graph.model, graph.key));
  takeRound(*roundBundle, policyDir, behaviors, round);
  // The final tables were checked against the scenario's settings; a round's were trained
  // with them too, against another opponent.
  Policies played;
  played.main = policyPartsOf(*roundBundle, policyDir, behaviors, options, {}, false);
  played.dir = policyDir;
  played.mainBundle = std::move(roundBundle);
  return played;
}

Policies Session::withPartner(Policies played, const std::filesystem::path& dir, int round) const {
  auto partnerBundle = std::make_shared<PolicyBundle>(loadPolicyBundle(dir, graph.model, graph.key));
  if (round > 0) takeRound(*partnerBundle, dir, behaviors, round);
  // A partner may have been trained with other settings (another opponent, other self-play
  // rounds): its tables need only fit the scenario's graph and grids.
  played.partner = policyPartsOf(*partnerBundle, dir, behaviors, options, {}, false);
  played.partnerDir = dir;
  played.partnerBundle = std::move(partnerBundle);
  return played;
}

std::unique_ptr<const Session> openSession(const SessionOptions& options, const SessionNeeds& needs) {
  Scenario scenario = checkedScenario(options);
  // The bundle first: what its manifest alone refuses is said before the graph is loaded.
  std::string graphKey, policyNote;
  std::filesystem::path policyDir;
  if (needs.policy == PolicyNeed::Required) {
    policyDir = resolvePolicy(needs.policyDir, scenario, options, &graphKey);
  } else if (needs.policy == PolicyNeed::IfAvailable) {
    try {
      policyDir = resolvePolicy(needs.policyDir, scenario, options, &graphKey);
    } catch (const Error& e) {
      policyNote = e.what();
    }
  }
  if (needs.beforeGraph) needs.beforeGraph(scenario);
  GraphOptions graphOptions;
  graphOptions.key = std::move(graphKey);
  graphOptions.cacheDir = options.cacheDir;
  graphOptions.log = options.log;
  graphOptions.motion = needs.motion;
  graphOptions.plugins = options.plugins;
  if (needs.graphFrom && graphOptions.key.empty()) graphOptions.key = graphCacheKey(scenario);
  GraphResult graph;
  if (needs.graphFrom && needs.graphFrom->key == graphOptions.key && (!needs.motion || needs.graphFrom->db.skeleton)) {
    graph = *needs.graphFrom;
    // The capture's travel is the same; the grids' reaches are this scenario's.
    CaptureTravel clips = graph.travel;
    clips.reaches.clear();
    clips.warnings.clear();
    graph.travel = measureTravel(scenario, std::move(clips), graph.model, *options.plugins);
    if (options.log)
      options.log(fmt::format("graph: shared with the scenario already open ({})", graph.bundle.string()));
  } else {
    graph = obtainGraph(scenario, graphOptions);
  }

  auto session = std::make_unique<Session>(std::move(scenario));
  session->options = options;
  session->graph = std::move(graph);
  session->policyDir = std::move(policyDir);
  session->policyNote = std::move(policyNote);
  const Scenario& s = session->scenario;
  session->behaviors = buildBehaviors(s, session->plugins(), session->graph.model, session->graph.key);
  session->task = makeTask(s, session->behaviors);
  if (!session->policyDir.empty())
    session->policy = policyParts(session->policyDir, session->behaviors, session->graph, options, session->bundle);
  for (const Behavior& b : session->behaviors)
    session->search.push_back({b.discretizer.get(), b.reward.get(), b.weight, b.activation, b.stance});
  if (session->graph.db.skeleton) session->body = makeBodyTable(session->graph.db);
  return session;
}

nlohmann::json hitEventJson(const HitEvent& e) {
  return {{"time", e.time},
          {"attacker", e.attacker},
          {"target", e.target},
          {"part", e.target < 0 ? "target" : bodyPartName(e.part)},
          {"hand", e.hand == 0 ? "left" : "right"},
          {"limb", e.kick ? "foot" : "fist"},
          {"speed", e.speed},
          {"blocked", e.blocked},
          {"point", {e.point.x(), e.point.y(), e.point.z()}}};
}

}  // namespace mgrl
