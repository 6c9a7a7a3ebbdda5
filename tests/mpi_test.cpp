// mpi_value_iteration under a real `mpirun` on this machine (oversubscribed):
// the same table, bit for bit, as value_iteration, alone and across 2 and 3 ranks, on
// boxing's hit behaviour and on a learned-opponent behaviour; a rank killed mid-run fails
// the job naming it, and `--resume` ends with the uninterrupted table.
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "cli_support.hpp"
#include "learners/mpi_ranks.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/launch.hpp"
#include "mgrl/core/random.hpp"
#include "sanitizer.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace mpi_test {

using namespace mgrl;

namespace {

// mpirun on this machine only: more ranks than cores, as root too (CI runs as root).
// LeakSanitizer is off in the ranks: Open MPI keeps allocations until exit that it never
// frees, which would fail every rank; mgrl's own code runs leak-checked in the runs alone.
std::string mpirun(int ranks, const std::string& environment = "") {
  return "env OMPI_MCA_btl=self,vader OMPI_MCA_rmaps_base_oversubscribe=1 " + environment +
         (test::kAddressSanitizer ? " ASAN_OPTIONS=detect_leaks=0" : "") +
         " mpirun --allow-run-as-root --oversubscribe --bind-to none -np " + std::to_string(ranks);
}

struct MpiSandbox : test::CliSandbox {
  MpiSandbox() : CliSandbox("mgrl_mpi") {}
  test::Run run(const std::string& arguments, const std::string& prefix = "") {
    return test::runMgrl(arguments + where(), dir(), prefix);
  }
  std::string table(const std::string& out, const std::string& behavior) const {
    return test::readText(path(out) / (behavior + ".q.npy"));
  }
};

// The tests need mpirun and an mgrl built with MPI: scripts/setup.sh --test installs both.
void requireMpi(MpiSandbox& box) {
  const test::Run list = test::runMgrl("list", box.dir());
  REQUIRE(list.status == 0);
  INFO("mgrl list:\n" << list.out);
  REQUIRE(list.out.find("mpi_value_iteration") != std::string::npos);
  if (list.out.find("built without MPI") != std::string::npos)
    FAIL("this mgrl was built without MPI: run scripts/setup.sh --test (Open MPI) and build again");
  REQUIRE(std::system("command -v mpirun >/dev/null 2>&1") == 0);
}

std::string scenario(const char* name) {
  return test::shellWord(std::string(test::sourceDirectory()) + "/scenarios/" + name);
}

// boxing.yaml's hit behaviour on a coarser grid: 10 angles x 16 distances x 3 heights
// (under AddressSanitizer, about 7 times slower, 6 x 8 x 2).
const std::string kHit = std::string(" --behavior hit ") +
                         (test::kAddressSanitizer ? "--set behaviors.hit.discretizer.angles=6 "
                                                    "--set behaviors.hit.discretizer.distances=8 "
                                                    "--set behaviors.hit.discretizer.heights=2 "
                                                  : "--set behaviors.hit.discretizer.angles=10 "
                                                    "--set behaviors.hit.discretizer.heights=3 ") +
                         "--set behaviors.hit.learner.type=";

// spar_learned.yaml on 2 x 2 x 2 positions, one phase: 8 positions x 117 opponent states,
// two self-play rounds (the second plays the first's table, which every rank must have).
// Under AddressSanitizer one round on 2 ranks: the rounds took 164 s there, mostly
// tabulating and scoring them; Release runs cover the rounds.
// The tolerance is the scenario's: another learner type starts from its own defaults.
const std::string kSpar = std::string(" --set behaviors.spar.discretizer.sectors=2 ") +
                          "--set behaviors.spar.discretizer.rings=2 --set behaviors.spar.discretizer.headings=2 "
                          "--set behaviors.spar.environment.phases=1 --set behaviors.spar.environment.rounds=" +
                          (test::kAddressSanitizer ? "1" : "2") + " --set behaviors.spar.learner.type=";
// Three ranks (an uneven split, one rank more than cores) are covered by the hit behaviour;
// the learned opponent's rounds run on two (the suite's time).
const std::vector<int> kSparRanks = {2};
std::string sparLearner(const std::string& type) {
  return kSpar + type + " --set behaviors.spar.learner.tolerance=0.01";
}

// "identical", or where two saved tables first differ (not the bytes themselves).
std::string compareTables(const std::string& a, const std::string& b) {
  if (a == b) return "identical";
  std::size_t at = 0;
  while (at < a.size() && at < b.size() && a[at] == b[at]) ++at;
  return "sizes " + std::to_string(a.size()) + " and " + std::to_string(b.size()) + ", first difference at byte " +
         std::to_string(at);
}

}  // namespace

TEST_CASE("mpi_value_iteration gives value_iteration's table bit for bit, alone and across 2 and 3 ranks",
          "[mpi][cli][data][slow]") {
  MpiSandbox box;
  requireMpi(box);
  SECTION("boxing's hit behaviour") {
    const test::Run single =
        box.run("train " + scenario("boxing.yaml") + kHit + "value_iteration --out " + test::shellWord(box.path("vi")));
    INFO(single.err);
    REQUIRE(single.status == 0);
    const std::string reference = box.table("vi", "hit");
    REQUIRE(reference.size() > 1000);
    const test::Run alone = box.run("train " + scenario("boxing.yaml") + kHit + "mpi_value_iteration --json --out " +
                                    test::shellWord(box.path("alone")));
    INFO(alone.err);
    REQUIRE(alone.status == 0);
    CHECK(alone.report()["behaviors"]["hit"]["stats"]["ranks"] == 1);
    CHECK(compareTables(box.table("alone", "hit"), reference) == "identical");
    for (int ranks : {2, 3}) {
      const std::string out = "np" + std::to_string(ranks);
      const test::Run run = box.run("train " + scenario("boxing.yaml") + kHit + "mpi_value_iteration --json --out " +
                                        test::shellWord(box.path(out)),
                                    mpirun(ranks));
      INFO("mpirun -np " << ranks << ":\n" << run.err);
      REQUIRE(run.status == 0);
      // Rank 0 alone speaks: one JSON report on stdout, one progress line per stage.
      const nlohmann::json report = run.report();
      CHECK(report["behaviors"]["hit"]["stats"]["ranks"] == ranks);
      CHECK(report["behaviors"]["hit"]["stats"]["bytes_sent_per_sweep_busiest_rank"].get<double>() > 0);
      CHECK(compareTables(box.table(out, "hit"), reference) == "identical");
      CHECK(test::lines(run.err).size() < 12);
    }
  }
  SECTION("a learned-opponent behaviour (spar_learned.yaml, smaller)") {
    const test::Run single = box.run("train " + scenario("spar_learned.yaml") + sparLearner("value_iteration") +
                                     " --out " + test::shellWord(box.path("vi")));
    INFO(single.err);
    REQUIRE(single.status == 0);
    const std::string reference = box.table("vi", "spar"), round1 = box.table("vi", "spar-round1");
    REQUIRE(round1.empty() == test::kAddressSanitizer);
    REQUIRE(reference.size() > 1000);
    for (int ranks : kSparRanks) {
      const std::string out = "np" + std::to_string(ranks);
      const test::Run run = box.run("train " + scenario("spar_learned.yaml") + sparLearner("mpi_value_iteration") +
                                        " --out " + test::shellWord(box.path(out)),
                                    mpirun(ranks));
      INFO("mpirun -np " << ranks << ":\n" << run.err);
      REQUIRE(run.status == 0);
      CHECK(compareTables(box.table(out, "spar-round1"), round1) == "identical");
      CHECK(compareTables(box.table(out, "spar"), reference) == "identical");
    }
  }
}

TEST_CASE(
    "a rank killed in the middle of mpi_value_iteration fails the job naming it, --resume ends with the same table",
    "[mpi][cli][data][slow]") {
  MpiSandbox box;
  requireMpi(box);
  const std::string train = "train " + scenario("boxing.yaml") + kHit + "mpi_value_iteration --out ";
  const test::Run whole = box.run(train + test::shellWord(box.path("whole")), mpirun(2));
  INFO(whole.err);
  REQUIRE(whole.status == 0);

  // Rank 1 kills itself (SIGKILL, as a lost machine) after sweep 3 and its checkpoint.
  const std::string out = test::shellWord(box.path("killed"));
  const test::Run killed = box.run(train + out, mpirun(2, "MGRL_TEST_KILL=1:3"));
  INFO(killed.err);
  CHECK(killed.status != 0);
  CHECK(killed.err.find("rank 1") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(box.path("killed") / "manifest.json"));
  const std::filesystem::path checkpoint = box.path("killed.checkpoints") / "hit" / "state.json";
  REQUIRE(std::filesystem::exists(checkpoint));
  CHECK(nlohmann::json::parse(test::readText(checkpoint))["state"]["sweeps"] == 3);

  // The checkpoint holds the whole table: the job may resume on another number of ranks.
  const test::Run resumed = box.run(train + out + " --resume", mpirun(3));
  INFO(resumed.err);
  REQUIRE(resumed.status == 0);
  CHECK(resumed.err.find("resume: hit: continuing from the checkpoint") != std::string::npos);
  CHECK(compareTables(box.table("killed", "hit"), box.table("whole", "hit")) == "identical");
  CHECK_FALSE(std::filesystem::exists(box.path("killed.checkpoints")));
}

TEST_CASE("the launcher's rank and size are read from its environment, and bad values are refused by name",
          "[mpi][unit]") {
  // Each case sets the variables, reads them and puts the environment back as it was.
  struct Env {
    std::vector<std::pair<std::string, std::optional<std::string>>> saved;
    void set(const char* name, const char* value) {
      const char* old = std::getenv(name);
      saved.emplace_back(name, old ? std::optional<std::string>(old) : std::nullopt);
      if (value)
        ::setenv(name, value, 1);
      else
        ::unsetenv(name);
    }
    ~Env() {
      for (auto it = saved.rbegin(); it != saved.rend(); ++it)
        if (it->second)
          ::setenv(it->first.c_str(), it->second->c_str(), 1);
        else
          ::unsetenv(it->first.c_str());
    }
  };
  Env env;
  for (const char* name :
       {"OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE", "PMI_RANK", "PMI_SIZE", "PMIX_RANK", "SLURM_STEP_NUM_TASKS"})
    env.set(name, nullptr);
  LaunchedProcess alone = launchedProcess();
  CHECK(alone.rank == 0);
  CHECK(alone.size == 1);
  CHECK_FALSE(alone.byLauncher);

  env.set("OMPI_COMM_WORLD_RANK", "2");
  env.set("OMPI_COMM_WORLD_SIZE", "3");
  const LaunchedProcess open = launchedProcess();
  CHECK(open.rank == 2);
  CHECK(open.size == 3);
  CHECK(open.byLauncher);

  env.set("OMPI_COMM_WORLD_RANK", "3");
  REQUIRE_THROWS_WITH(launchedProcess(), "OMPI_COMM_WORLD_RANK: expected a rank below OMPI_COMM_WORLD_SIZE=3, found 3");
  env.set("OMPI_COMM_WORLD_RANK", "two");
  REQUIRE_THROWS_WITH(launchedProcess(),
                      "OMPI_COMM_WORLD_RANK: expected a whole number from 0 to 16777216 (set by an "
                      "MPI launcher), found 'two'");
  env.set("OMPI_COMM_WORLD_RANK", nullptr);
  env.set("PMIX_RANK", "1");
  env.set("SLURM_STEP_NUM_TASKS", "4");
  const LaunchedProcess slurm = launchedProcess();
  CHECK(slurm.rank == 1);
  CHECK(slurm.size == 4);
}

TEST_CASE("mpi_value_iteration --resume ignores a checkpoint whose sweep count is out of range, naming it",
          "[mpi][cli][data]") {
  // One process (no launcher): MGRL_TEST_KILL=0:3 kills it after sweep 3's checkpoint.
  MpiSandbox box;
  const std::string train = "train " + scenario("boxing.yaml") + kHit + "mpi_value_iteration --out ";
  const std::string out = test::shellWord(box.path("bundle"));
  REQUIRE(box.run(train + out, "env MGRL_TEST_KILL=0:3").status != 0);
  const std::filesystem::path state = box.path("bundle.checkpoints") / "hit" / "state.json";
  nlohmann::json checkpoint = nlohmann::json::parse(test::readText(state));
  REQUIRE(checkpoint["state"]["sweeps"] == 3);
  checkpoint["state"]["sweeps"] = 5000;  // over max_sweeps (1000), under a valid seal
  checkpoint["hash"] = manifestHash(checkpoint);
  std::ofstream(state) << checkpoint.dump(2);

  const test::Run resumed = box.run(train + out + " --resume");
  INFO(resumed.err);
  REQUIRE(resumed.status == 0);
  CHECK(resumed.err.find(state.string()) != std::string::npos);
  CHECK(resumed.err.find("state.sweeps") != std::string::npos);
  CHECK(resumed.err.find("ignoring the checkpoint") != std::string::npos);
  CHECK(resumed.err.find("no checkpoint to continue from, trained from the start") != std::string::npos);
  REQUIRE(box.run(train + test::shellWord(box.path("straight"))).status == 0);
  CHECK(compareTables(box.table("bundle", "hit"), box.table("straight", "hit")) == "identical");
}

// partitionByEndState: longest processing time first (Graham 1969), the load of a state
// being the actions that end at it. Checked against a hand-worked split and, on random
// loads, against the bound that greedy split guarantees.
namespace {

GridModel withLoads(const std::vector<std::uint32_t>& loads) {
  GridModel g;
  g.incomingBegin.assign(1, 0);
  for (const std::uint32_t load : loads) g.incomingBegin.push_back(g.incomingBegin.back() + load);
  return g;
}

std::vector<std::uint64_t> rankLoads(const std::vector<std::uint32_t>& loads, const std::vector<int>& owner,
                                     int ranks) {
  std::vector<std::uint64_t> sum(static_cast<std::size_t>(ranks), 0);
  for (std::size_t s = 0; s < loads.size(); ++s) sum[static_cast<std::size_t>(owner[s])] += loads[s];
  return sum;
}

}  // namespace

TEST_CASE("the MPI split gives each state to one rank, largest first to the least loaded", "[mpi]") {
  // By hand, 2 ranks: 5 -> r0 (5, 0); 3 -> r1 (5, 3); 3 -> r1 (5, 6); 2 -> r0 (7, 6);
  // 2 -> r1 (7, 8); 1 -> r0 (8, 8). States in the order 2, 0, 5, 1, 3, 4 by load, ties kept
  // in state order.
  const std::vector<std::uint32_t> loads = {3, 2, 5, 2, 1, 3};
  CHECK(partitionByEndState(withLoads(loads), 2) == std::vector<int>{1, 0, 0, 1, 0, 1});
  CHECK(rankLoads(loads, partitionByEndState(withLoads(loads), 2), 2) == std::vector<std::uint64_t>{8, 8});
  // One rank holds everything; more ranks than states give each state a rank of its own.
  CHECK(partitionByEndState(withLoads(loads), 1) == std::vector<int>(6, 0));
  const std::vector<int> alone = partitionByEndState(withLoads(loads), 8);
  CHECK(std::set<int>(alone.begin(), alone.end()).size() == 6);

  // Random loads: every state owned by a rank in range, and no rank more than the largest
  // state's load above the least loaded one (what the greedy choice guarantees).
  Rng rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<std::uint32_t> random(20 + rng.below(200));
    for (auto& load : random) load = static_cast<std::uint32_t>(rng.below(1000));
    const int ranks = 2 + static_cast<int>(rng.below(7));
    const std::vector<int> owner = partitionByEndState(withLoads(random), ranks);
    REQUIRE(owner.size() == random.size());
    CHECK(std::all_of(owner.begin(), owner.end(), [&](int r) { return r >= 0 && r < ranks; }));
    const std::vector<std::uint64_t> sum = rankLoads(random, owner, ranks);
    const auto [least, most] = std::minmax_element(sum.begin(), sum.end());
    INFO("trial " << trial << ": " << random.size() << " states over " << ranks << " ranks");
    CHECK(*most - *least <= *std::max_element(random.begin(), random.end()));
    CHECK(partitionByEndState(withLoads(random), ranks) == owner);  // deterministic
  }
}

}  // namespace mpi_test
