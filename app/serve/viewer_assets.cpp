// What `mgrl serve` loads once for every page (ViewerAssets): the opened scenario's
// session and, when it names one, the sparring scenario's beside it. The pages'
// worlds are viewer.cpp's.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/scenario/scenario.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/trials.hpp"
#include "serve/viewer_parts.hpp"

namespace mgrl::serve {

namespace fs = std::filesystem;

namespace {

// One scenario's assets; `graphFrom`: a graph already loaded that it may share.
std::shared_ptr<ViewerAssets> loadAssets(const ServeOptions& options, const GraphResult* graphFrom) {
  auto assets = std::make_shared<ViewerAssets>();
  assets->options = options;
  assets->options.log = {};  // never called from a retraining thread
  // With no --policy, a missing or stale default bundle is not an error: the search runs
  // and the page says how to train one. An explicit --policy must work.
  SessionNeeds needs;
  needs.policy = options.policy.empty() ? PolicyNeed::IfAvailable : PolicyNeed::Required;
  needs.policyDir = options.policy;
  needs.graphFrom = graphFrom;
  assets->session = openSession(options, needs);
  const Session& session = *assets->session;
  assets->played = session.policies();
  if (!session.policyNote.empty())
    assets->note = fmt::format(
        "No usable policy bundle ({}), so the online search runs instead. Train one with: "
        "mgrl train {}",
        session.policyNote, options.scenario.string());
  assets->criteria = trialCriteria(session.behaviors, session.plugins().conditions).first;
  std::vector<std::string> texts;
  for (const SuccessCriterion& c : assets->criteria) texts.push_back(c.describe());
  assets->criteriaText = fmt::format("{}", fmt::join(texts, ", or "));
  const StateActionModel& model = session.model();
  assets->sourcePoses = std::make_shared<const SourcePoses>(makeSourcePoses(session.graph.db));
  assets->meanOutDegree = std::max(1.0, static_cast<double>(model.actionCount()) /
                                            static_cast<double>(std::max<std::size_t>(1, model.stateCount())));
  return assets;
}

// --partner-policy: the second avatar of each sparring pair of `spar` (the assets
// that play sparring and crowds) plays that bundle greedily, as `mgrl simulate
// --partner-policy` does.
void loadPartner(ViewerAssets& spar, const ServeOptions& options) {
  if (options.partnerPolicy.empty()) return;
  const Session& session = *spar.session;
  if (!session.partnerName().empty())
    throw Error(
        fmt::format("--partner-policy: expected a scenario whose partners play the page's controller, found "
                    "{}, whose partner is its scripted opponent ({})",
                    session.scenario.path.string(), session.partnerName()));
  try {
    spar.played = session.withPartner(spar.played, options.partnerPolicy, options.partnerRound);
  } catch (const Error& e) {
    throw Error(fmt::format("--partner-policy: {}", e.what()));
  }
  const std::string round = options.partnerRound > 0 ? fmt::format(" (self-play round {})", options.partnerRound) : "";
  spar.partnerNote = fmt::format("The second fighter of each pair plays {}{}.", options.partnerPolicy.string(), round);
  if (options.log)
    options.log(fmt::format("serve: sparring partners play {}{}", options.partnerPolicy.string(), round));
}

}  // namespace

std::shared_ptr<const ViewerAssets> loadViewerAssets(const ServeOptions& options) {
  Session::checkPartnerChoice(options.partnerPolicy, options.partnerRound);
  std::shared_ptr<ViewerAssets> assets = loadAssets(options, nullptr);
  // Sparring and crowds play another scenario's behaviours when the scenario (or
  // --sparring-scenario) names one (the paper's approach and hit close in to
  // 0.66 m; boxing_spar.yaml keeps a fighting distance). A scene with a scripted opponent
  // (dodge) spars with its own.
  const Session& main = *assets->session;
  fs::path other;
  if (options.sparringScenario.empty()) {
    checkSparringScenario(main.scenario);
    other = main.scenario.sparringScenario;
  } else if (options.sparringScenario != "none")
    other = options.sparringScenario;
  if (other.empty()) {
    loadPartner(*assets, options);
    return assets;
  }
  if (!main.partnerName().empty())
    throw Error(
        fmt::format("--sparring-scenario: expected a scenario without a scripted opponent ({} spars with its "
                    "own: {}), found {}",
                    options.scenario.string(), main.partnerName(), other.string()));
  ServeOptions companion = options;
  companion.scenario = other;
  companion.policy.clear();
  companion.sparringScenario = "none";
  companion.sets.clear();
  for (const std::string& set : options.sets)
    if (set.rfind("world.", 0) == 0) companion.sets.push_back(set);
  if (options.log) options.log(fmt::format("serve: sparring and crowds play {}", other.string()));
  std::shared_ptr<ViewerAssets> sparring;
  try {
    sparring = loadAssets(companion, &main.graph);
    if (!sparring->session->partnerName().empty())
      throw Error(fmt::format("expected a scenario without a scripted opponent, found one ({})",
                              sparring->session->partnerName()));
    if (options.log)
      options.log(
          sparring->session->policy.empty()
              ? fmt::format("serve: {} has no usable policy bundle ({}); the online search plays it", other.string(),
                            sparring->session->policyNote)
              : fmt::format("serve: {} plays policy bundle {}", other.string(), sparring->session->policyDir.string()));
    sparring->note =
        fmt::format("Sparring plays {}'s behaviours ({}); target mode plays {}'s.{}{}", other.string(),
                    options.sparringScenario.empty() ? fmt::format("{}'s sparring_scenario", options.scenario.string())
                                                     : std::string("--sparring-scenario"),
                    options.scenario.string(), sparring->note.empty() ? "" : " ", sparring->note);
  } catch (const Error& e) {
    throw Error(fmt::format("sparring scenario {}: {}", other.string(), e.what()));
  }
  loadPartner(*sparring, options);
  assets->sparring = std::move(sparring);
  return assets;
}

}  // namespace mgrl::serve
