// Graph construction benchmark: the sparring scenario (about 12,000 frames at
// 30 fps) from loaded capture to state-action model, and how time grows with the number of
// frames (a prefix of the clips) in the scenario's mode and with all pairs compared
// (contact_event: none). Prints medians over several runs and the peak resident memory.
//   build/bench/mgrl_bench_graph [--runs N] [--data DIR]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <sys/resource.h>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/graph/motion_graph.hpp"
#include "mgrl/scenario/scenario.hpp"

namespace {

double peakMegabytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // kB on Linux
}

// A database of the first `clips` clips (sharing the loaded motions).
mgrl::MotionDatabase prefix(const mgrl::MotionDatabase& db, std::size_t clips) {
  mgrl::MotionDatabase part;
  part.skeleton = db.skeleton;
  part.roles = db.roles;
  part.frameTime = db.frameTime;
  part.clips.assign(db.clips.begin(), db.clips.begin() + static_cast<long>(clips));
  part.offsets.assign(db.offsets.begin(), db.offsets.begin() + static_cast<long>(clips) + 1);
  return part;
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path data;
  const int runs =
      mgrl::bench::parseRunArgs(argc, argv, "mgrl_bench_graph: motion graph construction on the sparring capture", 5, 0,
                                mgrl::bench::dataOption(data))
          .runs;
  try {
    const auto scenarioPath = std::filesystem::path(MGRL_SOURCE_DIR) / "scenarios" / "sparring.yaml";
    const mgrl::Scenario scenario = mgrl::loadScenario(scenarioPath, mgrl::dataDirectory(data));
    auto t0 = std::chrono::steady_clock::now();
    const mgrl::MotionDatabase db = mgrl::loadMotionDatabase(scenario.motion);
    const double load = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("sparring: %u frames in %zu files, loaded and annotated in %.3f s\n", db.frameCount(), db.clips.size(),
                load);

    auto time = [&](const mgrl::MotionDatabase& part, const mgrl::GraphParams& params, mgrl::StateActionModel* out) {
      std::vector<double> t;
      for (int r = 0; r < runs; ++r) {
        const auto start = std::chrono::steady_clock::now();
        mgrl::StateActionModel m = mgrl::buildStateActionModel(part, params);
        t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        if (out) *out = std::move(m);
      }
      return mgrl::bench::median(t);
    };
    mgrl::StateActionModel model;
    const double build = time(db, scenario.graph, &model);
    std::printf("graph build (%s, threshold %.2f): %.3f s median of %d -> %zu states, %zu actions, peak RSS %.0f MB\n",
                std::string(mgrl::contactEventName(scenario.graph.contactEvent)).c_str(), scenario.graph.threshold,
                build, runs, model.stateCount(), model.actionCount(), peakMegabytes());

    std::printf("\n%8s %10s %14s %14s\n", "frames", "pairs", "scenario (s)", "all pairs (s)");
    mgrl::GraphParams all = scenario.graph;
    all.contactEvent = mgrl::ContactEvent::None;
    all.threshold = 0.2;
    all.minStates = 1;
    for (std::size_t clips : {db.clips.size() / 4, db.clips.size() / 2, db.clips.size()}) {
      const mgrl::MotionDatabase part = prefix(db, std::max<std::size_t>(clips, 1));
      mgrl::GraphParams scenarioParams = scenario.graph;
      scenarioParams.minStates = 1;
      const double a = time(part, scenarioParams, nullptr);
      const double b = time(part, all, nullptr);
      const double n = part.frameCount();
      std::printf("%8u %10.3g %14.3f %14.3f\n", part.frameCount(), n * n, a, b);
    }
    std::printf("peak RSS %.0f MB (all-pairs mode keeps only bands of 34 rows, never the matrix)\n", peakMegabytes());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mgrl_bench_graph: %s\n", e.what());
    return 1;
  }
  return 0;
}
