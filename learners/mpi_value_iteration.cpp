// mpi_value_iteration: value_iteration's Jacobi sweeps (paper sec. 4.2's backup at every
// (vertex, action) pair) across the processes of an MPI job, for tables that
// outgrow one machine. Without a launcher it runs as one process, the same code.
//
// How the work and the table are split: by graph state. Rank r owns a set of states S_r,
// chosen so that each rank backs up about as many (action, vertex) pairs.
//  - It backs up every action that ENDS in one of its states: such a backup reads only the
//    rows of that end state (max over the next actions of Q interpolated at the landing
//    point), which rank r holds. It tabulates (reward, landing cell) for those actions only.
//  - It holds the table's block of every state in S_r (the values of the actions that
//    LEAVE them), and receives each sweep the new values of those actions from the ranks
//    that backed them up, in one MPI_Alltoallv. It measures the change on its block.
//  - Convergence is the global largest change (MPI_Allreduce, max), as value_iteration's.
// A backup reads the previous sweep's table only, in the same arithmetic as value_iteration
// (the framework's backup() and maxInterpolated()), so the table is the same, bit for bit,
// whatever the number of ranks. Why this split: a backup needs nothing during the sweep,
// and the exchange is one regular Alltoallv of whole rows. A split by vertex blocks (by
// opponent layer on a learned-opponent grid) would receive 1.0 to 1.6 times fewer bytes
// on the problems counted by bench/mpi_bench.cpp (docs/distributed.md), but it must fetch
// scattered rows of other blocks at the landing corners, with per-rank lists of them and
// a local numbering of the vertices it reads: left for later. No split can send one value
// per vertex instead of a row: the max is taken over interpolated Q (sec. 4.2), not
// interpolated after it.
//
// A rank holds the rows of its own states only. Every `checkpoint_every` sweeps rank 0
// gathers the whole table and saves it through the checkpointer: a lost rank costs the
// sweeps since. Rank 0 also gathers the final table, and every rank receives it when the
// caller needs it there (TrainContext::wholeTableEverywhere: a self-play round's table).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include <fmt/format.h>

#include "learners.hpp"
#include "mgrl/core/launch.hpp"
#include "mgrl/core/parallel.hpp"
#include "mpi_rank_share.hpp"
#include "mpi_ranks.hpp"

namespace mgrl::learners {

namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

using Transitions = std::vector<GridTransition, HugePageAllocator<GridTransition>>;

// The transitions of the actions this rank backs up (`mine`), when the caller did not
// tabulate the problem. Alone (K == 1), a raised context.stop ends it early and throws
// TrainInterrupted.
Transitions tabulateMine(const TrainContext& context, const std::vector<std::uint32_t>& mine, int K, unsigned threads) {
  const Problem& problem = context.problem;
  const std::size_t V = context.grid.vertexCount;
  Transitions local;
  std::vector<TargetState> vertex(V);
  for (std::size_t v = 0; v < V; ++v) vertex[v] = problem.grid.vertexState(v);
  local.resize(mine.size() * V);
  parallelFor(mine.size(), threads, [&](std::size_t i, unsigned) {
    if (K == 1 && context.stop && context.stop->load(std::memory_order_relaxed)) return;
    for (std::size_t v = 0; v < V; ++v) local[i * V + v] = tabulate(problem, mine[i], vertex[v]);
  });
  if (K == 1 && context.stop && context.stop->load()) throw TrainInterrupted(0, 0, false);
  return local;
}

// One rank's half of a sweep: the backups of the actions ending at its states, into the
// send buffer, then the exchange (backups()); the received values against its block of
// the table (settle()). The seconds of each are summed for the report.
class RankSweeps {
 public:
  // `local`: this rank's transitions, used unless `given` (the caller's tabulated or
  // compact model in `g`).
  RankSweeps(const GridModel& g, const RankShare& share, const Ranks& ranks, QTable& q, const Transitions& local,
             bool given, unsigned threads)
      : g_(g),
        share_(share),
        ranks_(ranks),
        q_(q),
        local_(local),
        given_(given),
        threads_(threads),
        send_(share.mine.size() * g.vertexCount),
        received_(ranks.size() > 1 ? share.theirs.size() * g.vertexCount : 0),
        recv_(ranks.size() > 1 ? received_.data() : send_.data()),
        tied_(g.hanging.empty() ? 0 : g.vertexCount, 0) {
    for (std::uint32_t v : g.hanging.vertex) tied_[v] = 1;
  }

  void backups() {
    const GridModel& g = g_;
    const std::size_t V = g.vertexCount;
    const std::vector<std::uint32_t>& held = share_.held;
    const std::vector<std::uint32_t>& slot = share_.slot;
    const bool given = given_;
    const QTable& q = q_;
    const auto began = Clock::now();
    parallelFor(held.size(), threads_, [&](std::size_t i, unsigned) {
      const std::uint32_t s = held[i];
      for (std::uint32_t k = g.incomingBegin[s]; k < g.incomingBegin[s + 1]; ++k) {
        const std::size_t a = g.incoming[k];
        float* values = &send_[static_cast<std::size_t>(slot[a]) * V];
        if (!given) {
          const GridTransition* t = &local_[static_cast<std::size_t>(slot[a]) * V];
          for (std::size_t v = 0; v < V; ++v) values[v] = backup(q, g, a, t[v]);
        } else if (g.compact()) {
          for (std::size_t v = 0; v < V; ++v) values[v] = backup(q, g, a, g.landing(a, v));
        } else {
          for (std::size_t v = 0; v < V; ++v) values[v] = backup(q, g, a, g.transition[a * V + v]);
        }
        g.hanging.apply(values);
      }
    });
    const auto exchanging = Clock::now();
    ranks_.exchange(send_.data(), share_.sendCount, recv_, share_.recvCount, V);
    seconds_[0] += std::chrono::duration<double>(exchanging - began).count();
    seconds_[1] += std::chrono::duration<double>(Clock::now() - exchanging).count();
  }

  // The largest change (as value_iteration measures it), written into the block when
  // `write`; else the Bellman residual (as bellmanResidual() measures it: in double,
  // hanging vertices skipped).
  double settle(bool write) {
    const GridModel& g = g_;
    const std::size_t V = g.vertexCount;
    const std::vector<std::uint32_t>& held = share_.held;
    const std::vector<std::uint32_t>& recvSlot = share_.recvSlot;
    const std::vector<std::uint8_t>& tied = tied_;
    const float* recv = recv_;
    QTable& q = q_;
    const auto began = Clock::now();
    std::vector<double> change(held.size(), 0.0);
    parallelFor(held.size(), threads_, [&](std::size_t i, unsigned) {
      const std::uint32_t s = held[i];
      const std::size_t n = q.actionsOf(s), begin = g.stateActionBegin[s];
      double largest = 0;
      for (std::size_t v = 0; v < V; ++v) {
        float* row = q.row(s, v);
        if (!write && !tied.empty() && tied[v]) continue;
        for (std::size_t j = 0; j < n; ++j) {
          const float value = recv[static_cast<std::size_t>(recvSlot[begin + j]) * V + v];
          if (write) {
            largest = std::max(largest, static_cast<double>(std::fabs(value - row[j])));
            row[j] = value;
          } else {
            largest = std::max(largest, std::fabs(static_cast<double>(value) - row[j]));
          }
        }
      }
      change[i] = largest;
    });
    double largest = 0;
    for (double c : change) largest = std::max(largest, c);
    seconds_[0] += std::chrono::duration<double>(Clock::now() - began).count();
    return largest;
  }

  double backupSeconds() const { return seconds_[0]; }    // backups and settling
  double exchangeSeconds() const { return seconds_[1]; }  // exchanging

 private:
  const GridModel& g_;
  const RankShare& share_;
  const Ranks& ranks_;
  QTable& q_;
  const Transitions& local_;
  bool given_;
  unsigned threads_;
  std::vector<float> send_, received_;
  float* recv_;
  std::vector<std::uint8_t> tied_;
  double seconds_[2] = {0, 0};
};

class MpiValueIteration final : public Learner {
 public:
  explicit MpiValueIteration(const Params& p)
      : tolerance_(p.number("tolerance")),
        maxSweeps_(static_cast<std::uint64_t>(p.integer("max_sweeps"))),
        threads_(static_cast<unsigned>(p.integer("threads"))),
        checkpointEvery_(static_cast<std::uint64_t>(p.integer("checkpoint_every"))) {}

  std::string type() const override { return "mpi_value_iteration"; }
  bool takesCompactModel() const override { return true; }
  bool tabulatesItself() const override { return true; }

  // A share of everything a sweep holds: the transitions (20 bytes a pair), the rows of
  // its states, the send and receive buffers (4 + 4 + 4); with several ranks, rank 0 also
  // holds the whole table (4) for checkpoints and the result: the busiest rank's figure.
  double bytesPerProcess(std::size_t actions, std::size_t vertices) const override {
    const double pairs = static_cast<double>(actions) * static_cast<double>(vertices);
    const int ranks = std::max(1, launchedProcess().size);
    const double perPair =
        (sizeof(GridTransition) + 3 * sizeof(float)) / static_cast<double>(ranks) + (ranks > 1 ? sizeof(float) : 0.0);
    return pairs * perPair + static_cast<double>(vertices) * (8 * sizeof(std::uint32_t) + sizeof(TargetState)) +
           static_cast<double>(actions) * 24;
  }

  TrainResult train(const TrainContext& context) const override {
    const Ranks ranks = Ranks::join();
    try {
      return run(context, ranks);
    } catch (const TrainInterrupted&) {
      throw;
    } catch (const std::exception& e) {
      ranks.failed(e);
      throw;
    }
  }

 private:
  TrainResult run(const TrainContext& context, const Ranks& ranks) const {
    const GridModel& g = context.grid;
    const Problem& problem = context.problem;
    const std::size_t V = g.vertexCount, A = g.actionCount;
    const int me = ranks.rank(), K = ranks.size();
    // Ranks sharing a machine share its cores.
    const unsigned threads =
        threads_ > 0 ? threads_ : std::max(1u, context.threads / static_cast<unsigned>(std::max(1, ranks.localSize())));
    TrainingClock clock;

    const RankShare share = shareOf(g, problem.model.actionFrom, me, K);
    const std::vector<int>& owner = share.owner;
    // This rank's transitions, unless the caller tabulated the problem (then its own).
    const bool given = !g.transition.empty() || g.compact();
    const Transitions local = given ? Transitions() : tabulateMine(context, share.mine, K, threads);
    // Training time starts after the tabulation, as for learners given a tabulated model.
    const double tabulateSeconds = clock.seconds();
    clock.leaveOut(tabulateSeconds);

    // The rows of this rank's states only (heldModel()). Rank 0 keeps the whole table too,
    // for checkpoints and the result, allocated when first needed.
    const StateActionModel model = heldModel(g, owner, me);
    QTable q(model, V);
    QTable whole;  // K > 1 only: with one rank `q` is the whole table
    auto wholeTable = [&]() -> QTable& {
      if (K == 1) return q;
      if (whole.vertexCount() == 0) whole = QTable(problem.model, V);
      return whole;
    };
    RankSweeps rank(g, share, ranks, q, local, given, threads);

    TrainResult result;
    const std::uint64_t pairs = static_cast<std::uint64_t>(V) * A;
    std::uint64_t sweeps = 0;
    double change = 0;
    bool converged = false;
    // Whether rank 0 checkpoints decides for every rank.
    double checkpointing[1] = {context.checkpointer && ranks.root() && checkpointEvery_ > 0 ? 1.0 : 0.0};
    ranks.maxAll(checkpointing, 1);
    if (checkpointing[0] > 0) {
      QTable dummy;
      resume(context, ranks, ranks.root() ? wholeTable() : dummy, q, g, owner, sweeps, change, result.curve);
    }
    auto save = [&] {
      QTable dummy;
      QTable& target = ranks.root() ? wholeTable() : dummy;
      ranks.gather(q, target, g, owner);
      if (!ranks.root()) return;
      json curve = json::array();
      for (const CurvePoint& p : result.curve) curve.push_back({p.updates, p.seconds, p.residual});
      context.checkpointer->save(
          {{"updates", sweeps * pairs}, {"sweeps", sweeps}, {"change", change}, {"curve", curve}}, target);
    };
    const int killRank = testKill("rank"), killSweep = testKill("sweep");
    while (sweeps < maxSweeps_) {
      rank.backups();
      change = rank.settle(true);
      ++sweeps;
      double global[2] = {change, context.stop && context.stop->load(std::memory_order_relaxed) ? 1.0 : 0.0};
      ranks.maxAll(global, 2);
      change = global[0];
      result.curve.push_back({sweeps * pairs, clock.seconds(), change, 0});
      if (context.observer && ranks.root()) context.observer->progress({sweeps * pairs, 0, clock.seconds(), change});
      const bool last = change < tolerance_ || sweeps == maxSweeps_;
      if (checkpointing[0] > 0 && !last && (sweeps % checkpointEvery_ == 0 || global[1] > 0)) {
        clock.leavingOut(save);
      }
      // A test of a lost rank (MGRL_TEST_KILL="RANK:SWEEP"): this rank kills itself, as a
      // crashed machine would, after that sweep's checkpoint.
      if (me == killRank && sweeps == static_cast<std::uint64_t>(killSweep)) std::raise(SIGKILL);
      if (change < tolerance_) {
        converged = true;
        break;
      }
      if (global[1] > 0 && !last) throw TrainInterrupted(sweeps * pairs, 0, checkpointing[0] > 0);
    }
    // The Bellman residual of the final table: one more round of backups, measured only.
    rank.backups();
    double residual[1] = {rank.settle(false)};
    ranks.maxAll(residual, 1);
    // The whole table to rank 0, and to every rank when the caller needs it there (a
    // self-play round's, which the next round's opponent plays); else the other ranks
    // return an empty table.
    QTable dummy;
    QTable& target = ranks.root() || context.wholeTableEverywhere ? wholeTable() : dummy;
    ranks.gather(q, ranks.root() ? target : dummy, g, owner);
    if (context.wholeTableEverywhere) ranks.broadcast(target.values().data(), target.values().size());
    double busiest[3] = {share.exchanged, rank.backupSeconds(), rank.exchangeSeconds()};  // the busiest rank's
    ranks.maxAll(busiest, 3);
    result.table = K == 1 ? std::move(q) : std::move(whole);
    result.updates = sweeps * pairs;
    result.finalResidual = residual[0];
    result.seconds = clock.seconds();
    result.stats = {{"sweeps", sweeps},
                    {"converged", converged},
                    {"last_change", change},
                    {"ranks", K},
                    {"threads_per_rank", threads},
                    {"tabulate_seconds", tabulateSeconds},
                    {"bytes_sent_per_sweep_busiest_rank", busiest[0]},
                    {"backup_seconds_busiest_rank", busiest[1]},
                    {"exchange_seconds_busiest_rank", busiest[2]}};
    if (context.observer && ranks.root())
      context.observer->note(
          fmt::format("{} rank{}, {} sweeps; the busiest rank sent {:.1f} MB a sweep, backed up for {:.2f} s and "
                      "exchanged for {:.2f} s",
                      K, K > 1 ? "s" : "", sweeps, busiest[0] / 1e6, busiest[1], busiest[2]));
    return result;
  }

  // Continues from rank 0's checkpoint, if any: its sweep count, change, curve and table
  // go to every rank.
  void resume(const TrainContext& context, const Ranks& ranks, QTable& whole, QTable& held, const GridModel& g,
              const std::vector<int>& owner, std::uint64_t& sweeps, double& change,
              std::vector<CurvePoint>& curve) const {
    std::string text;
    if (ranks.root()) {
      std::uint64_t maxSweeps = maxSweeps_;
      const auto check = [maxSweeps](const json& state, const ManifestReader& reader) {
        if (!state.is_object()) reader.fail("state", "an object", state);
        (void)reader.unsignedInteger(state, "state", "sweeps", maxSweeps);
        (void)reader.number(state, "state", "change");
        const json& points = reader.member(state, "state", "curve");
        if (!points.is_array()) reader.fail("state.curve", "an array", points);
        for (const json& p : points)
          if (!p.is_array() || p.size() != 3 || !p[0].is_number_unsigned() || !p[1].is_number() || !p[2].is_number())
            reader.fail("state.curve", "[updates, seconds, change] triples", p);
      };
      if (std::optional<json> state = context.checkpointer->loadChecked(whole, check)) text = state->dump();
    }
    ranks.broadcast(text);
    if (text.empty()) return;
    const json state = json::parse(text);
    sweeps = state["sweeps"].get<std::uint64_t>();
    change = state["change"].get<double>();
    for (const json& p : state["curve"])
      curve.push_back({p[0].get<std::uint64_t>(), p[1].get<double>(), p[2].get<double>(), 0});
    ranks.scatter(whole, held, g, owner);
  }

  // MGRL_TEST_KILL="RANK:SWEEP" (tests only): the rank, or the sweep; -1 when unset.
  static int testKill(std::string_view part) {
    const char* text = std::getenv("MGRL_TEST_KILL");
    if (!text) return -1;
    int rank = -1, sweep = -1;
    if (std::sscanf(text, "%d:%d", &rank, &sweep) != 2) return -1;
    return part == "rank" ? rank : sweep;
  }

  double tolerance_;
  std::uint64_t maxSweeps_;
  unsigned threads_;
  std::uint64_t checkpointEvery_;
};

}  // namespace

void registerMpiValueIteration(LearnerRegistry& registry) {
  registry.add({
    "mpi_value_iteration",
#if MGRL_HAVE_MPI
        "value_iteration across the processes of an MPI job (mpirun -np K mgrl train ...), the table split by "
        "graph state; the same table as value_iteration, bit for bit (docs/distributed.md)",
#else
        "unavailable: this mgrl was built without MPI (install libopenmpi-dev and rebuild); alone it runs "
        "as one process, value_iteration's table (docs/distributed.md)",
#endif
        {ParamSpec::number("tolerance", 1e-4, 1e-9, 1, "", "stop when no value changes more than this"),
         ParamSpec::integer("max_sweeps", 1000, 1, 1'000'000, "sweeps", "give up after this many sweeps"),
         threadsSpec(),
         ParamSpec::integer("checkpoint_every", 1, 0, 1'000'000, "sweeps",
                            "rank 0 gathers and saves the table after this many sweeps (0: never)")},
        [](const Params& p) { return std::make_unique<MpiValueIteration>(p); }
  });
}

}  // namespace mgrl::learners
