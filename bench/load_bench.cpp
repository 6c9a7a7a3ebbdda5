// Benchmark: loading all of ../shared/mocap (parse, unit conversion) and forward
// kinematics. Prints medians over several runs, since this machine is shared and noisy.
//
//   build/bench/mgrl_bench_load [--runs N] [--data DIR]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "mgrl/core/data_paths.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/motion/annotation.hpp"
#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/kinematics.hpp"
#include "mgrl/motion/motion_io.hpp"

using namespace mgrl;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path dataArg;
  const int runs = bench::parseRunArgs(argc, argv, "mgrl_bench_load: parsing every BVH and AMC file of the data folder",
                                       7, 0, bench::dataOption(dataArg))
                       .runs;
  const std::filesystem::path data = dataDirectory(dataArg);
  std::vector<std::filesystem::path> files;
  try {
    for (const auto& e : std::filesystem::recursive_directory_iterator(data))
      if (e.path().extension() == ".bvh" || e.path().extension() == ".amc") files.push_back(e.path());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mgrl_bench_load: %s\n", e.what());
    return 1;
  }
  std::sort(files.begin(), files.end());

  // Bytes include each AMC's ASF, which loading it reads.
  double bytes = 0;
  for (const auto& f : files) {
    bytes += static_cast<double>(std::filesystem::file_size(f));
    if (f.extension() == ".amc") bytes += static_cast<double>(std::filesystem::file_size(defaultAsfFor(f)));
  }

  std::vector<double> loadTimes, parseTimes, fkTimes, annotateTimes, hashTimes;
  // Hashing from memory (every cache key and bundle check): a 64 MB buffer.
  const std::string hashInput(std::size_t{64} << 20, 'x');
  std::size_t frames = 0, jointFrames = 0;
  for (int run = 0; run < runs; ++run) {
    // Whole load from disk, as `mgrl inspect` does it (read, parse, convert units).
    const auto t0 = Clock::now();
    std::vector<Motion> motions;
    motions.reserve(files.size());
    for (const auto& f : files) motions.push_back(loadMotion(f).motion);
    const auto t1 = Clock::now();
    loadTimes.push_back(seconds(t0, t1));

    // Parsing alone, from memory.
    std::vector<std::string> texts;
    texts.reserve(files.size());
    for (const auto& f : files) texts.push_back(readFile(f));
    const auto p0 = Clock::now();
    for (std::size_t i = 0; i < files.size(); ++i) {
      if (files[i].extension() == ".bvh") {
        (void)parseBvh(texts[i], files[i].string());
      } else {
        const AsfSkeleton asf = parseAsf(readFile(defaultAsfFor(files[i])), "asf");
        (void)parseAmc(texts[i], files[i].string(), asf);
      }
    }
    parseTimes.push_back(seconds(p0, Clock::now()));

    // Forward kinematics of every frame into one reused buffer.
    frames = jointFrames = 0;
    std::vector<Eigen::Quaterniond> rotations(64);
    std::vector<Eigen::Vector3d> positions(64);
    double sink = 0;
    const auto f0 = Clock::now();
    for (const Motion& m : motions) {
      for (std::size_t f = 0; f < m.frameCount(); ++f) {
        forwardKinematics(m, f, rotations, positions);
        sink += positions[m.skeleton().jointCount() - 1].x();
      }
      frames += m.frameCount();
      jointFrames += m.frameCount() * m.skeleton().jointCount();
    }
    fkTimes.push_back(seconds(f0, Clock::now()));
    if (sink == 12345.678) std::puts("");  // keep the loop

    const auto h0 = Clock::now();
    const std::uint64_t digest = hashBytes(hashInput);
    hashTimes.push_back(seconds(h0, Clock::now()));
    if (digest == 12345) std::puts("");

    const auto a0 = Clock::now();
    for (const Motion& m : motions) (void)annotate(m, findRoles(m.skeleton()));
    annotateTimes.push_back(seconds(a0, Clock::now()));
  }

  const double load = bench::median(loadTimes), parse = bench::median(parseTimes);
  const double fk = bench::median(fkTimes), ann = bench::median(annotateTimes);
  std::printf("files                 %zu (%.1f MB, %zu frames)\n", files.size(), bytes / 1e6, frames);
  std::printf("load all (disk)       %.3f s median of %d  (%.0f MB/s)\n", load, runs, bytes / 1e6 / load);
  std::printf("parse only (memory)   %.3f s median  (%.0f MB/s)\n", parse, bytes / 1e6 / parse);
  std::printf("forward kinematics    %.4f s median  (%.1f M joints/s, %.2f M frames/s)\n", fk,
              static_cast<double>(jointFrames) / fk / 1e6, static_cast<double>(frames) / fk / 1e6);
  std::printf("annotate all          %.3f s median\n", ann);
  std::printf("hash (xxh64, memory)  %.1f GB/s median\n", static_cast<double>(hashInput.size()) / bench::median(hashTimes) / 1e9);
  return 0;
}
