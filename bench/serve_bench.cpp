// Viewer benchmark (issue 14): what one page costs the server per frame, on the real boxing
// capture with policies trained by value iteration: simulating a frame with every joint
// posed and encoding it as the binary pose frame (docs/viewer-protocol.md), for the target
// mode, sparring and crowds of 60, 1,000 and 2,000; and the bytes on the wire.
// Medians of several runs (the machine is shared and noisy).
//
// Usage: mgrl_bench_serve [--quick] [--runs N]
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "app/learn_commands.hpp"
#include "bench_support.hpp"
#include "boxing_setup.hpp"
#include "mgrl/core/data_paths.hpp"
#include "serve/viewer.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

}  // namespace

int main(int argc, char** argv) {
  int runs = 5;
  int frames = 150;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      runs = 3;
      frames = 60;
    } else if (!std::strcmp(argv[i], "--runs") && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "usage: mgrl_bench_serve [--quick] [--runs N]\n");
      return 2;
    }
  }
  try {
    const mgrl::app::TrainOptions train = mgrl::bench::trainBoxingByValueIteration("serve");
    const fs::path scratch = train.cacheDir;
    mgrl::serve::ServeOptions options;
    static_cast<mgrl::app::LearnOptions&>(options) = train;
    options.policy = train.out;
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
    fs::remove_all(scratch);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mgrl_bench_serve: %s\n", e.what());
    return 1;
  }
  return 0;
}
