// Runtime benchmark (DESIGN.md sec. 7): the world on the real boxing capture with
// policies trained by value iteration.
//   - the paper's run (sec. 6.7): 30 sparring avatars for 1,000 frames (paper: 9 s);
//   - avatar-frames per second for control + collision, and with forward kinematics of
//     every joint each frame, from 2 to 10,000 avatars; memory per avatar;
//   - decision cost of the policy against the online search at several horizons.
// Medians of several runs (the machine is shared and noisy).
//
// Usage: mgrl_bench_runtime [--quick] [--runs N] [--threads T]
#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

#include <fmt/format.h>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "boxing_setup.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Heap bytes in use (glibc's count: freed memory that the allocator keeps for reuse is
// not counted, unlike resident growth after other worlds were freed).
double heapBytes() {
  const struct mallinfo2 info = ::mallinfo2();
  return static_cast<double>(info.uordblks + info.hblkhd);
}


}  // namespace

int main(int argc, char** argv) {
  unsigned threads = mgrl::defaultThreadCount();
  const mgrl::bench::RunArgs args = mgrl::bench::parseRunArgs(
      argc, argv, "mgrl_bench_runtime: decisions, poses and crowds of the boxing scenario", 5, 3, [&](CLI::App& app) {
        app.add_option("--threads", threads, "threads of the crowd runs")->check(CLI::Range(1, 1000));
      });
  const int runs = args.runs;
  const bool quick = args.quick;
  try {
    const mgrl::bench::TrainedBoxing train = mgrl::bench::trainBoxing("runtime");
    const fs::path scratch = train.options.cacheDir;
    mgrl::SessionNeeds needs;
    needs.policy = mgrl::PolicyNeed::Required;
    needs.policyDir = train.policy;
    const std::unique_ptr<const mgrl::Session> session = mgrl::openSession(train.options, needs);
    const mgrl::StateActionModel& model = session->model();
    const std::vector<mgrl::PolicyPart>& parts = session->policy;
    fs::remove_all(scratch);
    const mgrl::WorldParams& params = session->task.world;
    std::printf("boxing: %zu states, %zu actions, %zu joints, %.0f fps; %u threads; medians of %d runs\n",
                model.stateCount(), model.actionCount(), session->graph.db.skeleton->jointCount(), 1 / model.frameTime,
                threads, runs);

    auto setup = [&](std::size_t avatars, bool poses) {
      mgrl::WorldSetup s = session->worldSetup(avatars, 1, {"policy"});
      s.threads = threads;
      s.poses = poses;
      return s;
    };
    // Avatar-frames per second of `frames` frames (the world made outside the timing).
    auto rate = [&](std::size_t avatars, std::size_t frames, bool poses, std::size_t* hits = nullptr) {
      std::vector<double> samples;
      for (int r = 0; r < runs; ++r) {
        mgrl::World world(setup(avatars, poses));
        const auto start = Clock::now();
        world.run(frames);
        samples.push_back(static_cast<double>(avatars * frames) / since(start));
        if (hits) *hits = world.landedCount();
      }
      return mgrl::bench::median(samples);
    };

    // The paper's run.
    {
      std::size_t hits = 0;
      const double control = rate(30, 1000, false, &hits);
      const double withPoses = rate(30, 1000, true);
      std::printf("\npaper's run, 30 sparring avatars x 1000 frames (paper: 9 s, 3,300 avatar-frames/s):\n");
      std::printf("  control + collision: %8.4f s  %12.0f avatar-frames/s  (%zu hits)\n", 30000 / control, control, hits);
      std::printf("  with poses (FK):     %8.4f s  %12.0f avatar-frames/s\n", 30000 / withPoses, withPoses);
    }

    // Growth with the number of avatars.
    std::printf("\ngrowth (avatar-frames/s; targets: >= 1,000,000 control + collision, >= 300,000 with FK)\n");
    std::printf("  %8s %16s %16s %14s %14s\n", "avatars", "control", "with FK", "B/avatar", "B/avatar FK");
    const std::vector<std::size_t> counts = quick ? std::vector<std::size_t>{2, 100, 10000}
                                                  : std::vector<std::size_t>{2, 10, 100, 1000, 10000};
    for (const std::size_t n : counts) {
      const std::size_t controlFrames = std::max<std::size_t>(300, (quick ? 2'000'000 : 6'000'000) / n);
      const std::size_t fkFrames = std::max<std::size_t>(60, (quick ? 200'000 : 600'000) / n);
      const double control = rate(n, controlFrames, false);
      const double fk = rate(n, fkFrames, true);
      mgrl::World plain(setup(n, false)), posed(setup(n, true));
      std::printf("  %8zu %16.0f %16.0f %14zu %14zu\n", n, control, fk, plain.bytesPerAvatar(), posed.bytesPerAvatar());
    }
    // Measured memory: resident growth for 10,000 avatars with poses.
    {
      const double before = heapBytes();
      mgrl::World world(setup(10000, true));
      world.run(1);
      const double after = heapBytes();
      std::printf("  heap memory for 10,000 avatars with poses: %.1f MB (%.0f B per avatar)\n",
                  (after - before) / 1e6, (after - before) / 10000);
    }

    // Decision cost: the same queries (state, target) from a sparring run for every controller.
    {
      const std::vector<mgrl::bench::DecisionQuery> queries = mgrl::bench::decisionQueries(model);
      auto timeController = [&](mgrl::Controller& c, std::size_t count) {
        return mgrl::bench::decisionSeconds(c, queries, count, runs);
      };
      std::printf("\ndecision cost (same %zu random (state, target) queries)\n", queries.size());
      mgrl::PolicyController greedy(model, parts);
      mgrl::PolicyController varied(model, parts, params.variety);
      const double policy = timeController(greedy, queries.size());
      std::printf("  %-28s %12.3f us\n", "policy (greedy)", policy * 1e6);
      std::printf("  %-28s %12.3f us\n", "policy (top 3, margin 0.1)", timeController(varied, queries.size()) * 1e6);
      const std::vector<mgrl::SearchPart>& searchParts = session->search;
      const mgrl::EnvironmentModel& environment = *session->task.environment;
      const double gamma = session->task.gamma;
      struct Horizon {
        int actions;
        double seconds;
      };
      const std::vector<Horizon> horizons = quick ? std::vector<Horizon>{{1, 0}, {2, 0}, {3, 0}}
                                                  : std::vector<Horizon>{{1, 0}, {2, 0}, {3, 0}, {8, 0.5}, {4, 0}};
      for (const Horizon& h : horizons) {
        mgrl::OnlineSearchController search(model, environment, searchParts, mgrl::SearchHorizon{h.actions, h.seconds}, gamma);
        const std::size_t count = h.actions >= 4 || h.seconds > 0 ? 20 : h.actions == 3 ? 200 : queries.size();
        const double cost = timeController(search, count);
        const std::string name = h.seconds > 0 ? fmt::format("online_search {:.1f} s", h.seconds)
                                               : fmt::format("online_search {} action{}", h.actions, h.actions > 1 ? "s" : "");
        std::printf("  %-28s %12.3f us  (%8.0fx the policy)\n", name.c_str(), cost * 1e6, cost / policy);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mgrl_bench_runtime: %s\n", e.what());
    return 1;
  }
  return 0;
}
