// Memory benchmark: what this machine's memory gives a loop like the learners'
// hot loops, as a yardstick for docs/performance.md's bounds.
//   - sequential read bandwidth over a buffer far larger than the caches;
//   - random cache lines: 64-byte lines at random addresses, read in batches of
//     independent loads (as Q-learning's prefetched transition records and Q rows are),
//     lines per second and GB/s;
//   - dependent random loads (a pointer chase): the latency of one miss.
// One and two threads; medians of several runs (the machine is shared and noisy).
//
// Usage: mgrl_bench_memory [--megabytes N] [--runs N]
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <thread>
#include <vector>

#include "bench_args.hpp"
#include "bench_support.hpp"
#include "mgrl/core/huge_pages.hpp"
#include "mgrl/core/random.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr std::size_t kLine = 64;
constexpr std::size_t kWordsPerLine = kLine / sizeof(std::uint64_t);

// Where results go, so that the compiler keeps the loops.
std::atomic<std::uint64_t> sink{0};

// Sum of every word of [begin, end): vectorised with the widest registers the machine has
// (the learners' row loops are built the same way), the hardware prefetches.
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
std::uint64_t sequential(const std::uint64_t* begin, const std::uint64_t* end) {
  std::uint64_t sum = 0;
  for (const std::uint64_t* p = begin; p < end; ++p) sum += *p;
  return sum;
}

// One word of each of the given lines: independent loads, as many in flight as the core allows.
std::uint64_t gather(const std::uint64_t* words, const std::uint32_t* lines, std::size_t count) {
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < count; ++i) sum += words[static_cast<std::size_t>(lines[i]) * kWordsPerLine];
  return sum;
}

// Runs f(thread) on `threads` threads at once; returns the wall time.
template <class F>
double timed(unsigned threads, F f) {
  const auto start = Clock::now();
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back([&f, t] { f(t); });
  f(0);
  for (auto& thread : pool) thread.join();
  return since(start);
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t megabytes = 1024;
  const int runs =
      mgrl::bench::parseRunArgs(argc, argv, "mgrl_bench_memory: this machine's memory latency and bandwidth", 5, 0,
                                [&](CLI::App& app) {
                                  app.add_option("--megabytes", megabytes, "size of the buffer (MB)")
                                      ->check(CLI::Range(std::size_t{64}, std::size_t{1} << 20));
                                })
          .runs;
  const std::size_t lines = megabytes * (std::size_t{1} << 20) / kLine;
  // On transparent huge pages, as the Q tables and tabulated models are (HugePageAllocator).
  std::vector<std::uint64_t, mgrl::HugePageAllocator<std::uint64_t>> words(lines * kWordsPerLine);
  std::iota(words.begin(), words.end(), std::uint64_t{0});  // touched: no page faults while timed
  std::printf("buffer %zu MB (%zu lines of %zu bytes); medians of %d runs\n", megabytes, lines, kLine, runs);

  // Random lines, and a random cycle through them for the chase.
  mgrl::Rng rng(11);
  constexpr std::size_t kGathered = 16'000'000;
  std::vector<std::uint32_t> randomLines(kGathered);
  for (auto& l : randomLines) l = static_cast<std::uint32_t>(rng.below(lines));

  for (const unsigned threads : {1u, 2u}) {
    std::vector<double> seq, rand;
    for (int r = 0; r < runs; ++r) {
      const std::size_t share = words.size() / threads;
      seq.push_back(timed(threads, [&](unsigned t) { sink.fetch_add(sequential(&words[t * share], &words[(t + 1) * share])); }));
      const std::size_t part = kGathered / threads;
      rand.push_back(timed(threads, [&](unsigned t) { sink.fetch_add(gather(words.data(), &randomLines[t * part], part)); }));
    }
    const double seqSeconds = mgrl::bench::median(seq), randSeconds = mgrl::bench::median(rand);
    std::printf("%u thread%s: sequential read %.1f GB/s; random lines %.0f M lines/s (%.1f GB/s of lines)\n", threads,
                threads > 1 ? "s" : " ", static_cast<double>(words.size() * 8) / seqSeconds / 1e9,
                static_cast<double>(kGathered) / randSeconds / 1e6,
                static_cast<double>(kGathered * kLine) / randSeconds / 1e9);
  }

  // Reads from the second-level cache: a 128 KB block per thread (a value-iteration sweep
  // reads the Q rows of one end state, about 100 KB for the paper-size hit problem, from
  // there), re-read many times.
  {
    constexpr std::size_t kBlockWords = (std::size_t{128} << 10) / sizeof(std::uint64_t), kRepeats = 20000;
    for (const unsigned threads : {1u, 2u}) {
      std::vector<double> samples;
      samples.reserve(static_cast<std::size_t>(runs));
      for (int r = 0; r < runs; ++r)
        samples.push_back(timed(threads, [&](unsigned t) {
          const std::uint64_t* block = &words[t * 4 * kBlockWords];
          std::uint64_t sum = 0;
          for (std::size_t k = 0; k < kRepeats; ++k) sum += sequential(block, block + kBlockWords) + k;
          sink.fetch_add(sum);
        }));
      std::printf("%u thread%s: reads from a 128 KB block (L2) %.0f GB/s\n", threads, threads > 1 ? "s" : " ",
                  static_cast<double>(threads * kRepeats * kBlockWords * 8) / mgrl::bench::median(samples) / 1e9);
    }
  }

  // Latency: each load's address depends on the previous one (a single random cycle).
  {
    const std::size_t chase = std::min<std::size_t>(lines, 8'000'000);
    std::vector<std::uint32_t> order(chase);
    std::iota(order.begin(), order.end(), 0u);
    for (std::size_t i = chase - 1; i > 0; --i) std::swap(order[i], order[rng.below(i + 1)]);
    const std::size_t stride = lines / chase;
    for (std::size_t i = 0; i < chase; ++i)
      words[order[i] * stride * kWordsPerLine] = order[(i + 1) % chase] * stride * kWordsPerLine;
    constexpr std::size_t kSteps = 4'000'000;
    std::vector<double> samples;
    for (int r = 0; r < runs; ++r) {
      std::uint64_t at = order[0] * stride * kWordsPerLine;
      const auto start = Clock::now();
      for (std::size_t i = 0; i < kSteps; ++i) at = words[at];
      samples.push_back(since(start));
      sink.fetch_add(at);
    }
    std::printf("dependent random loads (pointer chase over %zu lines): %.0f ns each\n", chase,
                mgrl::bench::median(samples) / kSteps * 1e9);
  }
  std::printf("[%llu]\n", static_cast<unsigned long long>(sink.load() % 10));
  return 0;
}
