// mgrl as a library: open a scenario, train its behaviours, run a world, read the hits.
// Usage: session_example [SCENARIO [SECONDS]]   (data: MGRL_DATA; cache: MGRL_CACHE)
#include <cstdio>
#include <string>
#include <vector>

#include "mgrl/learning/problem.hpp"
#include "mgrl/session/plugins.hpp"
#include "mgrl/session/session.hpp"

int main(int argc, char** argv) try {
  mgrl::SessionOptions options;
  options.scenario = argc > 1 ? argv[1] : "scenarios/boxing.yaml";
  const double seconds = argc > 2 ? std::stod(argv[2]) : 10;
  const auto session = mgrl::openSession(options);  // graph, behaviours, the task they share

  // Each behaviour's table by value iteration (paper sec. 4), then the tables as the policy.
  const auto learner = mgrl::builtinPlugins().learners.create(mgrl::ConfigNode::parse("{type: value_iteration}", "ex"));
  std::vector<mgrl::QTable> tables;
  tables.reserve(session->behaviors.size());  // the policy points into them
  for (const mgrl::Behavior& b : session->behaviors) {
    const mgrl::Problem problem = b.problem(session->model());
    const mgrl::GridModel grid = mgrl::GridModel::build(problem, 2);
    tables.push_back(learner->train({problem, grid, nullptr, nullptr, 2}).table);
    session->policy.push_back({b.discretizer.get(), &tables.back(), b.weight, b.activation, b.stance});
    std::printf("trained %s: %zu vertices\n", b.name.c_str(), grid.vertexCount);
  }

  // Four avatars sparring in the scenario's world, each run by the trained policy.
  mgrl::World world(session->worldSetup(4, /*seed=*/1, {"policy"}));
  world.run(static_cast<std::size_t>(seconds / session->model().frameTime));
  for (const mgrl::HitEvent& hit : world.events()) std::printf("%s\n", mgrl::hitEventJson(hit).dump().c_str());
  std::printf("%zu hits in %g s\n", world.events().size(), seconds);
} catch (const std::exception& e) {
  std::fprintf(stderr, "session_example: %s\n", e.what());
  return 1;
}
