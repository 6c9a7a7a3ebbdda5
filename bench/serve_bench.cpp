// Viewer benchmark: what one page costs the server per frame, on the real boxing
// capture with policies trained by value iteration: simulating a frame with every joint
// posed and encoding it as the binary pose frame (docs/viewer-protocol.md), for the target
// mode, sparring and crowds of 60, 1,000 and 2,000; and the bytes on the wire.
// Medians of several runs (the machine is shared and noisy).
//
// With --shared, also the shared time budget on the real server over loopback:
// what 15 pages of crowds of 2,000 on the online search at speed 4 leave to one light page
// (frames per second it receives, medians of the runs). With --flood, what 4 pages switching
// between a crowd of 2,000 and target mode at 150 messages a second leave to one light page
// and to a request every 50 ms (frames per second, longest gap, longest request).
//
// Usage: mgrl_bench_serve [--quick] [--runs N] [--shared] [--flood]
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "boxing_setup.hpp"
#include "mgrl/core/data_paths.hpp"
#include "page_load.hpp"
#include "serve/serve_command.hpp"
#include "serve/server.hpp"
#include "serve/viewer.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Seconds the light page is watched for in each --shared run (after 3 s for the crowds).
constexpr double kSharedSeconds = 6;
// Seconds of flooding in each --flood run.
constexpr double kFloodSeconds = 20;

}  // namespace

int main(int argc, char** argv) {
  bool shared = false, flood = false;
  const mgrl::bench::RunArgs args = mgrl::bench::parseRunArgs(
      argc, argv, "mgrl_bench_serve: the viewer's server under pages", 5, 3, [&](CLI::App& app) {
        app.add_flag("--shared", shared, "also time a light page beside crowds sharing the server");
        app.add_flag("--flood", flood, "also time a light page and requests beside pages flooding mode switches");
      });
  const int runs = args.runs;
  const int frames = args.quick ? 60 : 150;
  try {
    const mgrl::bench::TrainedBoxing train = mgrl::bench::trainBoxing("serve");
    const fs::path scratch = train.options.cacheDir;
    mgrl::serve::ServeOptions options;
    static_cast<mgrl::SessionOptions&>(options) = train.options;
    options.policy = train.policy;
    const auto assets = mgrl::serve::loadViewerAssets(options);

    std::printf("one page's cost per frame (simulate with poses + encode), medians of %d runs of %d frames\n", runs,
                frames);
    std::printf("%-22s %12s %14s %16s %14s\n", "mode", "ms/frame", "frame bytes", "bytes/avatar", "MB/s at 30 fps");
    struct Case {
      const char* name;
      const char* message;
    };
    const Case cases[] = {{"target (1 avatar)", R"({"type":"mode","mode":"target"})"},
                          {"sparring (2)", R"({"type":"mode","mode":"sparring"})"},
                          {"crowd of 60", R"({"type":"mode","mode":"crowd","avatars":60})"},
                          {"crowd of 1,000", R"({"type":"mode","mode":"crowd","avatars":1000})"},
                          {"crowd of 2,000", R"({"type":"mode","mode":"crowd","avatars":2000})"}};
    for (const Case& c : cases) {
      std::vector<double> perFrame;
      std::size_t bytes = 0, avatars = 0;
      for (int r = 0; r < runs; ++r) {
        mgrl::serve::ViewerSession session(assets);
        session.handle(c.message);
        for (int f = 0; f < 30; ++f) session.advance(1.0);  // every avatar has decided
        const auto start = Clock::now();
        for (int f = 0; f < frames; ++f) {
          session.advance(1.0);
          bytes = session.frame().size();
        }
        perFrame.push_back(since(start) / frames);
        avatars = session.avatars();
        (void)session.takeOutbox();
      }
      const double ms = mgrl::bench::median(perFrame) * 1e3;
      std::printf("%-22s %12.3f %14zu %16.1f %14.2f\n", c.name, ms, bytes,
                  static_cast<double>(bytes) / static_cast<double>(avatars), static_cast<double>(bytes) * 30 / 1e6);
    }
    if (flood) {
      mgrl::serve::ServerOptions serverOptions;
      serverOptions.port = 0;
      serverOptions.webRoot = mgrl::serve::webDirectory({});
      mgrl::serve::Server server(assets, serverOptions);
      std::thread thread([&] { server.run(); });
      std::vector<double> fps, gaps, longest, median;
      for (int r = 0; r < runs; ++r) {
        const mgrl::bench::FloodBesideLight m = mgrl::bench::floodBesideLight(server.port(), 4, 150, kFloodSeconds);
        fps.push_back(m.lightFramesPerSecond);
        gaps.push_back(m.lightLongestGap);
        longest.push_back(m.requestLongest);
        median.push_back(m.requestMedian);
        std::fprintf(stderr, "  run %d: %s\n", r + 1, m.summary().c_str());
      }
      server.stop();
      thread.join();
      std::printf(
          "\nmessages in the shared budget: 4 pages switching crowd/target at 150 messages/s beside one light "
          "page and a request every 50 ms, medians of %d runs of %.0f s\n",
          runs, kFloodSeconds);
      std::printf("  light page %.1f frames/s, longest gap %.2f s; requests %.1f ms median, %.1f ms longest\n",
                  mgrl::bench::median(fps), mgrl::bench::median(gaps), mgrl::bench::median(median) * 1e3,
                  mgrl::bench::median(longest) * 1e3);
    }
    if (shared) {
      mgrl::serve::ServerOptions serverOptions;
      serverOptions.port = 0;
      serverOptions.webRoot = mgrl::serve::webDirectory({});
      serverOptions.maxSessions = 16;
      mgrl::serve::Server server(assets, serverOptions);
      std::thread thread([&] { server.run(); });
      std::vector<double> fps, gaps, heavyFrames;
      for (int r = 0; r < runs; ++r) {
        const mgrl::bench::HeavyBesideLight m = mgrl::bench::heavyBesideLight(server.port(), 15, 3, kSharedSeconds);
        fps.push_back(m.lightFramesPerSecond);
        gaps.push_back(m.lightLongestGap);
        heavyFrames.push_back(static_cast<double>(m.heavyFrames));
        std::fprintf(stderr, "  run %d: %s\n", r + 1, m.summary().c_str());
      }
      server.stop();
      thread.join();
      std::printf("\nthe shared budget: 15 crowds of 2,000 (online search, speed 4) beside one light page, medians of %d "
                  "runs\n",
                  runs);
      std::printf("  light page %.1f frames/s, longest gap %.2f s; heavy pages %.0f frames in all per run\n",
                  mgrl::bench::median(fps), mgrl::bench::median(gaps), mgrl::bench::median(heavyFrames));
    }
    fs::remove_all(scratch);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mgrl_bench_serve: %s\n", e.what());
    return 1;
  }
  return 0;
}
