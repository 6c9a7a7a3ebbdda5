#pragma once
/// \file
/// The Learner seam (DESIGN.md sec. 4): a learner turns a tabulated problem into a QTable.
/// Learners never see YAML, BVH or files: parameters arrive through the registry, progress
/// leaves through a TrainObserver, and long runs save their whole state through a
/// Checkpointer so that a resumed run ends with the same table as an uninterrupted one.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/registry.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/learning/q_table.hpp"

namespace mgrl {

/// One point of a training curve.
struct CurvePoint {
  std::uint64_t updates = 0;  ///< actions taken (Q-learning) or (vertex, action) backups (value iteration)
  double seconds = 0;         ///< training time so far
  double residual = 0;        ///< max Bellman residual of the table at this point
  double meanResidual = 0;
};

struct TrainProgress {
  std::uint64_t updates = 0, total = 0;  ///< total 0 when unknown (value iteration)
  double seconds = 0;
  double residual = -1;  ///< the latest measured residual, -1 before the first
};

class TrainObserver {
 public:
  virtual ~TrainObserver() = default;
  /// Called often (at most every few milliseconds of work); cheap.
  virtual void progress(const TrainProgress&) {}
  /// A line worth telling the user now (say, which of several starts is being trained).
  virtual void note(const std::string&) {}

  /// How many snapshots of the table this observer wants along training (0, the default:
  /// none, and learners then do no extra work). Learners take them at about this many
  /// evenly spaced points of their work (q_learning: budget * i / n for i = 1..n;
  /// value_iteration: its sweep count estimated from the shrinking change, the last sweep
  /// always; adaptive_value_iteration: the end of each refinement round), so a learning
  /// curve can be measured on policies, not only on residuals.
  virtual std::size_t snapshotCount() const { return 0; }
  /// The table as it stands at a snapshot point: `point` has the updates and training
  /// seconds so far and the Bellman residual there; `grid` is the grid the table's
  /// vertices belong to when the learner refined it (null: the problem's own grid). The
  /// table is valid only during the call. Learners leave the time spent here (and on a
  /// residual measured only for it) out of their training seconds, and train the same
  /// table as without snapshots.
  virtual void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) {
    (void)table, (void)point, (void)grid;
  }
};

/// The number of snapshots `observer` wants (0 for none or no observer).
inline std::size_t snapshotsWanted(const TrainObserver* observer) { return observer ? observer->snapshotCount() : 0; }

/// A learner's training time: the wall time since the clock started, plus a resumed run's
/// earlier time, less what the learner leaves out (snapshots, checkpoints, tabulation).
class TrainingClock {
 public:
  /// Starts now, `secondsBefore` already trained.
  explicit TrainingClock(double secondsBefore = 0) : before_(secondsBefore) {}
  /// The training time so far (s).
  double seconds() const { return before_ + std::chrono::duration<double>(Clock::now() - start_).count() - left_; }
  /// Leaves `seconds` already spent outside training out.
  void leaveOut(double seconds) { left_ += seconds; }
  /// Runs `work` and leaves its time out.
  template <class Work>
  void leavingOut(Work&& work) {
    const auto began = Clock::now();
    std::forward<Work>(work)();
    left_ += std::chrono::duration<double>(Clock::now() - began).count();
  }

 private:
  using Clock = std::chrono::steady_clock;
  double before_;
  double left_ = 0;
  Clock::time_point start_ = Clock::now();
};

/// Gives `observer` a snapshot; the time it takes is left out of `clock`'s training time.
inline void takeSnapshot(TrainObserver& observer, TrainingClock& clock, const QTable& table, const CurvePoint& point,
                         const Discretizer* grid = nullptr) {
  clock.leavingOut([&] { observer.snapshot(table, point, grid); });
}

/// A learner's check of its own saved state, run by Checkpointer::loadChecked() before the
/// state or table is used: reads every member it will trust (presence, type, range) and
/// throws mgrl::Error if one is wrong, through `reader`, which names the checkpoint's file,
/// with the state's members at path "state" (e.g. `run/hit/state.json: state.walk.state:
/// expected an integer in [0, 41], found '97'`). It may keep what it read (the caller's
/// variables), but only as the result of a loadChecked() that returns a state.
using StateCheck = std::function<void(const nlohmann::json& state, const ManifestReader& reader)>;

/// Where a learner keeps a resumable state. A checkpoint is the learner's own JSON plus a
/// table; `load` returns the last one saved for the same problem, if any.
class Checkpointer {
 public:
  virtual ~Checkpointer() = default;
  virtual void save(const nlohmann::json& state, const QTable& table) = 0;
  virtual std::optional<nlohmann::json> load(QTable& table) = 0;

  /// load(), accepting the state only if `check` passes it: what learners call. A
  /// checkpointer that reports damaged checkpoints (DirectoryCheckpointer) overrides this
  /// to report a rejected state the same way, name its file, leave `table` unchanged and
  /// return std::nullopt, so the learner starts over. This default, for checkpointers that
  /// cannot report, refuses instead of starting over silently: it throws mgrl::Error
  /// `checkpoint: <check's message>` (with `table` already overwritten by load(); the
  /// caller must not use it).
  virtual std::optional<nlohmann::json> loadChecked(QTable& table, const StateCheck& check) {
    std::optional<nlohmann::json> state = load(table);
    if (state && check) check(*state, ManifestReader("checkpoint"));
    return state;
  }
};

struct TrainResult {
  QTable table;
  std::uint64_t updates = 0;
  double seconds = 0;  ///< training time of this table, resumed runs included
  double finalResidual = 0;
  std::vector<CurvePoint> curve;
  nlohmann::json stats = nlohmann::json::object();  ///< learner-specific figures
  /// The grid the table's vertices belong to when the learner refined it (adaptive
  /// learners); null when it is the problem's own grid.
  std::shared_ptr<const Discretizer> grid;
};

struct TrainContext {
  const Problem& problem;
  const GridModel& grid;
  TrainObserver* observer = nullptr;
  Checkpointer* checkpointer = nullptr;  ///< may be null: no checkpoints
  unsigned threads = 1;
  /// When set and true (e.g. by a Ctrl-C handler), the learner stops at its next safe
  /// point, saves a checkpoint if it can, and throws TrainInterrupted.
  const std::atomic<bool>* stop = nullptr;
  /// A distributed learner (mpi_value_iteration) returns the whole table on every process
  /// when set (a self-play round's table, which the next round's opponent plays), else on
  /// rank 0 only (the others return an empty table: rank 0 writes the bundle).
  bool wholeTableEverywhere = false;
};

/// Thrown by Learner::train when TrainContext::stop was raised.
class TrainInterrupted : public Error {
 public:
  TrainInterrupted(std::uint64_t updates, std::uint64_t total, bool checkpointed)
      : Error("training interrupted"), updates_(updates), total_(total), checkpointed_(checkpointed) {}
  std::uint64_t updates() const { return updates_; }   ///< work done when stopped
  std::uint64_t total() const { return total_; }       ///< 0 when unknown (value iteration)
  bool checkpointed() const { return checkpointed_; }  ///< a checkpoint of this point was saved

 private:
  std::uint64_t updates_, total_;
  bool checkpointed_;
};

class Learner {
 public:
  virtual ~Learner() = default;
  virtual std::string type() const = 0;
  virtual TrainResult train(const TrainContext& context) const = 0;
  /// Throws mgrl::Error (what was expected, what was found) if this learner cannot train on
  /// `grid`, so that commands refuse a mismatch before training anything.
  virtual void checkGrid(const Discretizer& grid) const { (void)grid; }
  /// True if train() takes a compact GridModel (GridModel::buildCompact: rewards only, the
  /// landings found per backup) as well as a tabulated one, with the same result.
  virtual bool takesCompactModel() const { return false; }
  /// True if train() tabulates the problem itself, so that a caller may hand it
  /// GridModel::frame() instead of a tabulated model (mpi_value_iteration: each process
  /// tabulates only the actions it backs up). Given a tabulated or compact model, such a
  /// learner uses it.
  virtual bool tabulatesItself() const { return false; }
  /// The bytes training on `actions` x `vertices` needs in this process, when the learner
  /// knows better than GridModel::trainingBytes (a distributed learner holds a share of the
  /// model); negative: it does not.
  virtual double bytesPerProcess(std::size_t actions, std::size_t vertices) const {
    (void)actions, (void)vertices;
    return -1;
  }
  /// The most grid vertices training on `grid` will hold a table for: the grid's own,
  /// or, for a learner that refines it, its vertex budget.
  virtual std::size_t trainingVertices(const Discretizer& grid) const { return grid.vertexCount(); }
  /// Q tables of trainingVertices() rows held beside the model and the two of a solve
  /// (GridModel::trainingBytes), e.g. the other starts' results until one is kept.
  virtual std::size_t extraTables() const { return 0; }
};

using LearnerRegistry = Registry<Learner>;

}  // namespace mgrl
