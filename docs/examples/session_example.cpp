// mgrl as a library: open a scenario, train its behaviours, let four boxers spar, print the hits.
// Usage: session_example [SCENARIO [SECONDS]]   (data: MGRL_DATA; cache: MGRL_CACHE)
#include <cstdio>
#include <string>

#include "builtin_plugins.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/training.hpp"

int main(int argc, char** argv) try {
  mgrl::SessionOptions options;
  options.scenario = argc > 1 ? argv[1] : "scenarios/boxing.yaml";
  options.plugins = &mgrl::builtinPlugins();  // every learner, grid, reward and model mgrl ships
  const double seconds = argc > 2 ? std::stod(argv[2]) : 10;
  const auto session = mgrl::openSession(options);  // graph, behaviours, the task they share
  // Every behaviour trained as `mgrl train` trains it, by value iteration (paper sec. 4), kept in memory.
  mgrl::TrainSettings settings;
  settings.save = false;
  settings.learner = session->plugins().learners.create(mgrl::ConfigNode::parse("{type: value_iteration}", "example"));
  mgrl::Trained trained = mgrl::trainScenario(*session, settings);
  for (const auto& [name, b] : trained.bundle.behaviors)
    std::printf("trained %s: %zu vertices\n", name.c_str(), b.table.vertexCount());
  // Four avatars sparring in the scenario's world, each run by the trained tables.
  const auto policy = mgrl::policyPartsOf(trained.bundle, "", session->behaviors, session->options);
  mgrl::World world(session->worldSetup(4, /*seed=*/1, {"policy"}, policy));
  world.run(static_cast<std::size_t>(seconds / session->model().frameTime));
  for (const mgrl::HitEvent& hit : world.events()) std::printf("%s\n", mgrl::hitEventJson(hit).dump().c_str());
  std::printf("%zu hits in %g s\n", world.events().size(), seconds);
} catch (const std::exception& e) {
  std::fprintf(stderr, "session_example: %s\n", e.what());
  return 1;
}
