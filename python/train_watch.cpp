// A C++ learner trained from Python (train_watch.hpp).
#include "train_watch.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "mgrl/session/training.hpp"

namespace mgrl::python {
namespace {

// A residual for Python: None where the learner reports -1 (none measured yet).
py::object residualOrNone(double residual) { return residual < 0 ? py::object(py::none()) : py::float_(residual); }

// Training run off the Python thread: its progress handed to a Python callback about ten
// times a second, what it says printed on Python's stderr, Ctrl-C turned into the learner's
// stop request (as the command line's handler does), the callback's own exception stopping
// it too.
class Relay final : public TrainObserver {
 public:
  void progress(const TrainProgress& p) override {
    std::lock_guard lock(mutex_);
    last_ = p;
    fresh_ = true;
  }
  void note(const std::string& line) override {
    std::lock_guard lock(mutex_);
    notes_.push_back(line);
  }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override;
  // Snapshots of the table along training (compare's learning curves): copied here, on
  // the learner's thread, and handed to Python by take().
  explicit Relay(std::size_t snapshots = 0) : snapshots_(snapshots) {}
  std::size_t snapshotCount() const override { return snapshots_; }
  struct Taken {
    CurvePoint point;
    std::vector<float> table;  // (A, V) action-major
    std::size_t vertices = 0;
  };
  std::vector<Taken> takeSnapshots() {
    std::lock_guard lock(mutex_);
    std::vector<Taken> out;
    out.swap(taken_);
    return out;
  }

  // What came since the last call.
  std::optional<TrainProgress> take(std::vector<std::string>& notes) {
    std::lock_guard lock(mutex_);
    notes.swap(notes_);
    notes_.clear();
    if (!fresh_) return std::nullopt;
    fresh_ = false;
    return last_;
  }

 private:
  std::size_t snapshots_ = 0;
  std::mutex mutex_;
  TrainProgress last_;
  bool fresh_ = false;
  std::vector<std::string> notes_;
  std::vector<Taken> taken_;
};

void Relay::snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) {
  if (grid) return;  // a refined grid's table is not offered to Python
  Taken t{point, table.actionMajor(), table.vertexCount()};
  std::lock_guard lock(mutex_);
  taken_.push_back(std::move(t));
}

// Hands each behaviour's (and round's) progress and snapshots to the one relay.
class Forward final : public TrainListener {
 public:
  explicit Forward(Relay& relay) : relay_(relay) {}
  void progress(const TrainProgress& p) override { relay_.progress(p); }
  std::size_t snapshotCount() const override { return relay_.snapshotCount(); }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override {
    relay_.snapshot(table, point, grid);
  }

 private:
  Relay& relay_;
};

}  // namespace

Trained trainWatched(const Session& session, const TrainSettings& settings, const py::object& progress,
                     std::size_t snapshots, const py::object& onSnapshot) {
  const std::string& behavior = settings.behavior;
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  std::optional<Trained> result;
  std::exception_ptr failure;
  Relay relay(onSnapshot.is_none() ? 0 : snapshots);
  TrainHooks hooks;
  hooks.log = [&relay](const std::string& line) { relay.note(line); };
  hooks.progressLines = false;  // the progress callback has them
  hooks.listen = [&relay](const Behavior&, const std::vector<Behavior>&, const GraphResult&) {
    return std::make_unique<Forward>(relay);
  };
  hooks.stop = &stop;
  std::thread worker([&] {
    try {
      result = trainScenario(session, settings, hooks);
    } catch (...) {
      failure = std::current_exception();
    }
    std::lock_guard lock(mutex);
    done = true;
    finished.notify_all();
  });
  bool interrupted = false;
  std::optional<py::error_already_set> callbackError;
  for (;;) {
    bool over = false;
    {
      py::gil_scoped_release release;
      std::unique_lock lock(mutex);
      over = finished.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; });
    }
    std::vector<std::string> notes;
    const std::optional<TrainProgress> p = relay.take(notes);
    for (const std::string& line : notes) toStderr(fmt::format("mgrl: {}", line));
    // Calls a Python callback; its exception stops training (Ctrl-C while it ran
    // surfaces there as KeyboardInterrupt: the same stop as below).
    auto call = [&](const py::object& callback, py::dict d) {
      if (callbackError || interrupted) return;
      d["behavior"] = behavior;
      try {
        callback(d);
      } catch (py::error_already_set& e) {
        if (e.matches(PyExc_KeyboardInterrupt))
          interrupted = true;
        else
          callbackError.emplace(std::move(e));
        stop = true;
      }
    };
    for (Relay::Taken& t : relay.takeSnapshots()) {
      py::array_t<float> table({t.table.size() / std::max<std::size_t>(1, t.vertices), t.vertices});
      std::copy(t.table.begin(), t.table.end(), table.mutable_data());
      py::dict d;
      d["updates"] = t.point.updates;
      d["seconds"] = t.point.seconds;
      d["residual"] = residualOrNone(t.point.residual);
      d["table"] = table;
      call(onSnapshot, d);
    }
    if (p && !progress.is_none()) {
      py::dict d;
      d["updates"] = p->updates;
      d["total"] = p->total;
      d["seconds"] = p->seconds;
      d["residual"] = residualOrNone(p->residual);  // None until the learner has measured one
      call(progress, d);
    }
    if (over) break;
    if (!interrupted && PyErr_CheckSignals() != 0) {  // Ctrl-C: KeyboardInterrupt is pending
      PyErr_Clear();
      interrupted = true;
      stop = true;
    }
  }
  worker.join();
  if (callbackError) throw *callbackError;
  if (failure) {
    try {
      std::rethrow_exception(failure);
    } catch (const TrainInterrupted& e) {
      if (!interrupted) throw;
      const std::string where = e.total() > 0 ? fmt::format(" at {} of {} updates", e.updates(), e.total())
                                              : fmt::format(" after {} updates", e.updates());
      PyErr_SetString(PyExc_KeyboardInterrupt,
                      fmt::format("interrupted while training {}{}; nothing was kept", behavior, where).c_str());
      throw py::error_already_set();
    }
  }
  if (interrupted) {  // it finished before it saw the request: still the user's Ctrl-C
    PyErr_SetString(PyExc_KeyboardInterrupt, fmt::format("interrupted after training {}", behavior).c_str());
    throw py::error_already_set();
  }
  return std::move(*result);
}

}  // namespace mgrl::python
