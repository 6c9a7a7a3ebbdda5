// mgrl._core: the session stage (framework/session) bound to Python with pybind11 (issue 41).
// The package mgrl (python/mgrl/__init__.py) re-exports what users call. Arrays are NumPy
// views of the session's own memory where they can be (the graph's), else arrays made once.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/config.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/session/episodes.hpp"
#include "mgrl/session/evaluate.hpp"
#include "mgrl/session/plugins.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/session/compare_report.hpp"
#include "mgrl/session/compare_tables.hpp"

namespace py = pybind11;

namespace mgrl::python {
namespace {

// A NumPy array over `data` (shape `shape`, C order) that keeps `owner` alive: no copy.
template <class T>
py::array_t<T> view(const T* data, std::vector<py::ssize_t> shape, py::handle owner) {
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t stride = sizeof(T);
  for (std::size_t i = shape.size(); i-- > 0;) {
    strides[i] = stride;
    stride *= shape[i];
  }
  py::array_t<T> a(shape, strides, data, owner);
  // Read-only: the session's graph is shared by everything made from it.
  reinterpret_cast<py::detail::PyArray_Proxy*>(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// `sets` as the command line takes them: a dict {key: value} or a list of "key=value".
std::vector<std::string> setsOf(const py::object& sets) {
  std::vector<std::string> out;
  if (sets.is_none()) return out;
  if (py::isinstance<py::dict>(sets)) {
    for (const auto& [key, value] : sets.cast<py::dict>()) {
      std::string text;
      if (py::isinstance<py::bool_>(value))
        text = value.cast<bool>() ? "true" : "false";
      else
        text = py::str(value).cast<std::string>();
      out.push_back(fmt::format("{}={}", py::str(key).cast<std::string>(), text));
    }
    return out;
  }
  for (const auto& item : sets) {
    if (!py::isinstance<py::str>(item))
      throw Error(fmt::format("sets: expected a dict {{key: value}} or a list of 'key=value' strings, found an item "
                              "of type {}",
                              py::str(py::type::of(item).attr("__name__")).cast<std::string>()));
    out.push_back(item.cast<std::string>());
  }
  return out;
}

std::string typeName(const py::handle& value) {
  return py::str(py::type::of(value).attr("__name__")).cast<std::string>();
}

// "(1438, 100)": a NumPy array's shape as Python prints it.
std::string shapeText(const py::array& a) {
  std::vector<py::ssize_t> dims(a.shape(), a.shape() + a.ndim());
  if (dims.size() == 1) return fmt::format("({},)", dims[0]);
  return fmt::format("({})", fmt::join(dims, ", "));
}

// Lines for the user (what the command line prints on stderr) go to Python's sys.stderr,
// so that notebooks show them; callable from any thread.
void toStderr(const std::string& line) {
  py::gil_scoped_acquire gil;
  py::module_::import("sys").attr("stderr").attr("write")(line + "\n");
}

// A C++ learner run off the Python thread: its progress handed to a Python callback about
// ten times a second, Ctrl-C turned into the learner's stop request (as the command line's
// handler does), the callback's own exception stopping it too.
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
  // Snapshots of the table along training (compare's learning curves): copied here, on
  // the learner's thread, and handed to Python by take().
  explicit Relay(std::size_t snapshots = 0) : snapshots_(snapshots) {}
  std::size_t snapshotCount() const override { return snapshots_; }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override {
    if (grid) return;  // a refined grid's table is not offered to Python
    Taken t{point, table.actionMajor(), table.vertexCount()};
    std::lock_guard lock(mutex_);
    taken_.push_back(std::move(t));
  }
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

// Tabulates `problem` and trains `learner` on it on a worker thread while this thread
// (holding the GIL between waits) relays progress and watches for Ctrl-C. Throws
// KeyboardInterrupt (Python's) when interrupted, the callback's exception if it raised.
TrainResult trainWatched(const std::string& behavior, const Learner& learner, const Problem& problem,
                         const py::object& progress, std::size_t snapshots = 0,
                         const py::object& onSnapshot = py::none()) {
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  std::optional<TrainResult> result;
  std::exception_ptr failure;
  Relay relay(onSnapshot.is_none() ? 0 : snapshots);
  std::thread worker([&] {
    try {
      const GridModel g = learner.takesCompactModel() ? GridModel::buildCompact(problem, threads, &stop)
                                                      : GridModel::build(problem, threads, &stop);
      result = learner.train({problem, g, &relay, nullptr, threads, &stop});
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
    for (const std::string& line : notes) toStderr(fmt::format("train {}: {}", behavior, line));
    for (Relay::Taken& t : relay.takeSnapshots()) {
      if (callbackError || interrupted) break;
      try {
        py::array_t<float> table({t.table.size() / std::max<std::size_t>(1, t.vertices), t.vertices});
        std::copy(t.table.begin(), t.table.end(), table.mutable_data());
        py::dict d;
        d["behavior"] = behavior;
        d["updates"] = t.point.updates;
        d["seconds"] = t.point.seconds;
        d["residual"] = t.point.residual;
        d["table"] = table;
        onSnapshot(d);
      } catch (py::error_already_set& e) {
        if (e.matches(PyExc_KeyboardInterrupt))
          interrupted = true;
        else
          callbackError.emplace(std::move(e));
        stop = true;
      }
    }
    if (p && !progress.is_none() && !callbackError && !interrupted) {
      try {
        py::dict d;
        d["behavior"] = behavior;
        d["updates"] = p->updates;
        d["total"] = p->total;
        d["seconds"] = p->seconds;
        d["residual"] = p->residual;
        progress(d);
      } catch (py::error_already_set& e) {
        // Ctrl-C while the callback ran surfaces there: the same stop as below.
        if (e.matches(PyExc_KeyboardInterrupt))
          interrupted = true;
        else
          callbackError.emplace(std::move(e));
        stop = true;
      }
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

// The tabulated problem of one behaviour as NumPy arrays (python/mgrl/__init__.py,
// Problem): what value iteration backs up, corner by corner.
struct ProblemArrays {
  std::string behavior;
  py::array_t<float> rewards, weights, discount;
  py::array_t<std::int32_t> corners, nextState, outIndptr, outIndices;
  py::array_t<double> vertices;
  std::size_t states = 0, actions = 0, vertexCount = 0;
  double tabulateSeconds = 0;  ///< the C++ tabulation (GridModel::build), what learners pay too
  double arraysSeconds = 0;    ///< then filling these arrays from it
  int dimension = 0;
};

class PySession {
 public:
  PySession(const std::filesystem::path& scenario, const py::object& data, const py::object& cache, const py::object& sets) {
    SessionOptions options;
    options.scenario = scenario;
    if (!data.is_none()) options.dataDir = data.cast<std::filesystem::path>();
    if (!cache.is_none()) options.cacheDir = cache.cast<std::filesystem::path>();
    options.sets = setsOf(sets);
    options.log = toStderr;
    SessionNeeds needs;
    needs.motion = false;  // the model is what Python works on; a cached graph starts fast
    py::gil_scoped_release release;
    session_ = openSession(options, needs);
  }

  const Session& session() const { return *session_; }

  std::vector<std::string> behaviorNames() const {
    std::vector<std::string> names;
    for (const Behavior& b : session_->behaviors) names.push_back(b.name);
    return names;
  }

  const Behavior& behavior(const std::string& name) const {
    for (const Behavior& b : session_->behaviors)
      if (b.name == name) return b;
    throw Error(fmt::format("behavior: expected one of the scenario's behaviours ({}), found '{}'",
                            fmt::join(behaviorNames(), ", "), name));
  }

  ProblemArrays problem(const std::string& name) const {
    const Behavior& b = behavior(name);
    const Discretizer& grid = *b.discretizer;
    // Speed layers fit the formula as they are: a backup lands exactly on its layer, so a
    // cell's corners are those of one layer. A kd-tree's hanging vertices do not: their
    // rows are interpolated from other vertices after each backup, not backed up.
    if (!grid.hanging().empty())
      throw Error(fmt::format("problem({}): its grid ({}) has {} hanging vertices, whose values are interpolated, "
                              "not backed up; only grids without them are offered to Python yet",
                              name, grid.type(), grid.hanging().size()));
    const StateActionModel& model = session_->model();
    const Problem problem = b.problem(model);
    GridModel g;
    const auto started = std::chrono::steady_clock::now();
    {
      py::gil_scoped_release release;
      g = GridModel::build(problem, std::max(1u, std::thread::hardware_concurrency()));
    }
    const double tabulated = since(started);
    const std::size_t A = g.actionCount, V = g.vertexCount, K = std::size_t{1} << g.dimension;
    ProblemArrays p;
    p.behavior = name;
    p.states = model.stateCount();
    p.actions = A;
    p.vertexCount = V;
    p.dimension = g.dimension;
    p.rewards = py::array_t<float>({A, V});
    p.corners = py::array_t<std::int32_t>({A, V, K});
    p.weights = py::array_t<float>({A, V, K});
    float* r = p.rewards.mutable_data();
    std::int32_t* c = p.corners.mutable_data();
    float* w = p.weights.mutable_data();
    // Filled on every core, an action at a time (each writes its own rows); the GIL is
    // released: the arrays are not yet visible to Python.
    {
      py::gil_scoped_release release;
      parallelFor(A, std::max(1u, std::thread::hardware_concurrency()), [&](std::size_t a, unsigned) {
        for (std::size_t v = 0; v < V; ++v) {
          const GridTransition& t = g.transition[a * V + v];
          const std::size_t at = a * V + v;
          r[at] = t.reward;
          if (t.cell < 0) {
            std::fill(c + at * K, c + at * K + K, -1);
            std::fill(w + at * K, w + at * K + K, 0.0f);
            continue;
          }
          float weight[8];
          cornerWeights(g.dimension, {t.frac[0], t.frac[1], t.frac[2]}, weight);
          const std::uint32_t* corner = &g.corners[static_cast<std::size_t>(t.cell) << g.dimension];
          for (std::size_t k = 0; k < K; ++k) {
            c[at * K + k] = static_cast<std::int32_t>(corner[k]);
            w[at * K + k] = weight[k];
          }
        }
      });
    }
    p.discount = py::array_t<float>(A);
    std::copy(g.discount.begin(), g.discount.end(), p.discount.mutable_data());
    p.nextState = py::array_t<std::int32_t>(A);
    std::copy(g.actionTo.begin(), g.actionTo.end(), p.nextState.mutable_data());
    p.outIndptr = py::array_t<std::int32_t>(model.stateCount() + 1);
    std::copy(model.stateActionBegin.begin(), model.stateActionBegin.end(), p.outIndptr.mutable_data());
    // The model numbers each state's out-actions contiguously: indices are 0 .. A-1.
    p.outIndices = py::array_t<std::int32_t>(A);
    for (std::size_t a = 0; a < A; ++a) p.outIndices.mutable_data()[a] = static_cast<std::int32_t>(a);
    // Each vertex as the grid's coordinates (angle, distance, height, ... as its axes say),
    // and on a grid with speed layers its layer's speed last.
    const int D = grid.dimension(), columns = D + (grid.layerAxis() ? 1 : 0);
    p.vertices = py::array_t<double>({V, static_cast<std::size_t>(columns)});
    for (std::size_t v = 0; v < V; ++v) {
      const TargetState e = grid.vertexState(v);
      const auto coordinates = grid.coordinates(e);
      double* row = p.vertices.mutable_data() + v * static_cast<std::size_t>(columns);
      for (int d = 0; d < D; ++d) row[d] = coordinates[static_cast<std::size_t>(d)];
      if (grid.layerAxis()) row[D] = e.speed;
    }
    p.tabulateSeconds = tabulated;
    p.arraysSeconds = since(started) - tabulated;
    return p;
  }

  // Any registered learner on one behaviour; the table as (A, V) float32.
  py::array_t<float> train(const std::string& name, const py::object& learner, const py::object& sets,
                           const py::object& progress, std::size_t snapshots, const py::object& onSnapshot) {
    const Behavior& b = behavior(name);
    // The scenario's learner block; another learner type starts from its defaults (as
    // --set behaviors.B.learner.type=OTHER resets the block).
    nlohmann::json config = b.config.value("learner", nlohmann::json::object());
    if (!learner.is_none() && config.value("type", std::string()) != learner.cast<std::string>())
      config = {{"type", learner.cast<std::string>()}};
    for (const std::string& set : setsOf(sets)) {
      const std::size_t eq = set.find('=');
      if (eq == std::string::npos) throw Error(fmt::format("sets: expected 'key=value', found '{}'", set));
      config[set.substr(0, eq)] = nlohmann::json::parse(set.substr(eq + 1), nullptr, false).is_discarded()
                                      ? nlohmann::json(set.substr(eq + 1))
                                      : nlohmann::json::parse(set.substr(eq + 1));
    }
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
      throw Error(fmt::format("progress: expected a callable taking a dict, or None, found an object of type {}",
                              typeName(progress)));
    if (!onSnapshot.is_none() && !PyCallable_Check(onSnapshot.ptr()))
      throw Error(fmt::format("on_snapshot: expected a callable taking a dict, or None, found an object of type {}",
                              typeName(onSnapshot)));
    if (snapshots > 1000) throw Error(fmt::format("snapshots: expected at most 1000, found {}", snapshots));
    const auto made = builtinPlugins().learners.create(ConfigNode::parse(config.dump(), fmt::format("{} learner", name)));
    made->checkGrid(*b.discretizer);
    const TrainResult result =
        trainWatched(name, *made, b.problem(session_->model()), progress, snapshots, onSnapshot);
    if (result.grid)
      throw Error(fmt::format("train: the learner {} refined its own grid ({} vertices); tables on refined grids are "
                              "not offered to Python yet",
                              made->type(), result.table.vertexCount()));
    nlohmann::json curve = nlohmann::json::array();
    for (const CurvePoint& c : result.curve) curve.push_back({c.updates, c.seconds, c.residual, c.meanResidual});
    lastTrain_ = {{"behavior", name},          {"learner", made->type()},
                  {"updates", result.updates}, {"seconds", result.seconds},
                  {"final_residual", result.finalResidual}, {"curve", curve},
                  {"stats", result.stats}};
    return tableArray(result.table);
  }

  // What the last train() reported: updates, seconds, final_residual, curve, stats.
  py::object lastTrain() const {
    if (lastTrain_.is_null()) return py::none();
    return py::module_::import("json").attr("loads")(lastTrain_.dump());
  }

  // compare's table measures against a reference table on the same behaviour's grid:
  // {"value_rmse", "greedy_agreement", "reference_interpolated"} (mgrl/session/compare_tables.hpp).
  py::dict compareTables(const std::string& name, const py::object& table, const py::object& reference) const {
    const Behavior& b = behavior(name);
    const QTable q = tableFrom(b, table), r = tableFrom(b, reference);
    const std::vector<double> positions = vertexPositions(*b.discretizer);
    Comparison c;
    {
      py::gil_scoped_release release;
      c = mgrl::compareTables(q, positions, r, positions, *b.discretizer);
    }
    py::dict d;
    d["value_rmse"] = c.rmse;
    d["greedy_agreement"] = c.agreement;
    d["reference_interpolated"] = c.interpolated;
    return d;
  }

  // A NumPy Q table for behaviour `b`: float32 of shape (A, V) with finite values. Refused
  // otherwise with one message naming both shapes, before anything is allocated for it.
  QTable tableFrom(const Behavior& b, const py::handle& value) const {
    const StateActionModel& model = session_->model();
    const std::size_t A = model.actionCount(), V = b.discretizer->vertexCount();
    const std::string where = fmt::format("tables['{}']", b.name);
    if (!py::isinstance<py::array>(value))
      throw Error(fmt::format("{}: expected a NumPy float32 array of shape ({}, {}), found an object of type {}", where,
                              A, V, typeName(value)));
    const auto a = py::reinterpret_borrow<py::array>(value);
    if (a.ndim() != 2 || static_cast<std::size_t>(a.shape(0)) != A || static_cast<std::size_t>(a.shape(1)) != V)
      throw Error(fmt::format("{}: expected shape ({}, {}) ({} actions of the graph x {} vertices of {}'s {} grid), "
                              "found shape {}",
                              where, A, V, A, V, b.name, b.discretizer->type(), shapeText(a)));
    if (!a.dtype().is(py::dtype::of<float>()))
      throw Error(fmt::format("{}: expected dtype float32, found {} (convert with table.astype(numpy.float32))", where,
                              py::str(a.dtype()).cast<std::string>()));
    const auto c = py::array_t<float, py::array::c_style>::ensure(a);  // a copy only if strided
    const float* d = c.data();
    for (std::size_t i = 0; i < A * V; ++i)
      if (!std::isfinite(d[i]))
        throw Error(fmt::format("{}: expected finite values, found {} at [{}, {}]", where, d[i], i / V, i % V));
    QTable q(model, V);
    q.setActionMajor({d, A * V});
    return q;
  }

  // A behaviour's table from the scenario's trained bundle when it holds a current one,
  // else trained here with the scenario's learner (once per session; said on stderr).
  std::shared_ptr<PolicyBehavior> otherTable(const Behavior& b) {
    if (const auto found = others_.find(b.name); found != others_.end()) return found->second;
    const Session& session = *session_;
    const std::filesystem::path dir =
        defaultPolicyDirectory(session.options.cacheDir.empty() ? defaultCacheDirectory() : session.options.cacheDir,
                               session.scenario, session.graph.key);
    std::string why = "no trained bundle";
    if (std::filesystem::exists(dir / "manifest.json")) {
      try {
        if (!bundle_) bundle_ = std::make_unique<PolicyBundle>(loadPolicyBundle(dir, session.model(), session.graph.key));
        const auto found = bundle_->behaviors.find(b.name);
        if (found == bundle_->behaviors.end()) {
          why = "no table for it in the trained bundle";
        } else if (found->second.key != b.key) {
          why = "the trained bundle's table has other settings";
        } else if (!found->second.grid.empty()) {
          why = "the trained bundle's table is on a refined grid";
        } else {
          auto table = std::make_shared<PolicyBehavior>(found->second);
          others_[b.name] = table;
          return table;
        }
      } catch (const Error& e) {
        why = fmt::format("the trained bundle is unusable: {}", e.what());
      }
    }
    toStderr(fmt::format("mgrl: {} ({}): training {} with {} first; `mgrl train {} --behavior {}` keeps one", b.name,
                         why, b.name, b.learner->type(), session.scenario.path.string(), b.name));
    TrainResult result = trainWatched(b.name, *b.learner, b.problem(session.model()), py::none());
    if (result.grid)
      throw Error(fmt::format("{}: its learner {} refines its grid; train it with `mgrl train` first", b.name,
                              b.learner->type()));
    auto table = std::make_shared<PolicyBehavior>();
    table->key = b.key;
    table->record = {{"learner", b.learner->type()}, {"config", b.config}, {"updates", result.updates}};
    table->table = std::move(result.table);
    table->vertices = vertexPositions(*b.discretizer);
    table->gridType = b.discretizer->type();
    table->grid = b.discretizer->structure();
    others_[b.name] = table;
    return table;
  }

  // The scenario's behaviours, in its order: `tables` (a dict of NumPy arrays) for those it
  // names, otherTable() for the rest. `learnerName` goes into the given ones' records.
  struct Tables {
    std::map<std::string, std::shared_ptr<PolicyBehavior>> behaviors;
    std::vector<PolicyPart> parts;
  };
  Tables tablesFor(const py::object& tables, const std::string& learnerName) {
    if (!py::isinstance<py::dict>(tables))
      throw Error(fmt::format("tables: expected a dict {{behaviour name: NumPy (A, V) float32 table}}, found an object "
                              "of type {}",
                              typeName(tables)));
    Tables out;
    for (const auto& [key, value] : tables.cast<py::dict>()) {
      const std::string name = py::str(key).cast<std::string>();
      const Behavior& b = behavior(name);
      auto given = std::make_shared<PolicyBehavior>();
      given->key = b.key;
      given->record = {{"learner", learnerName},
                       {"trained_in", "python"},
                       {"config", b.config},
                       {"weight", b.weight},
                       {"activation", std::string(activationName(b.activation))},
                       {"grid", b.discretizer->describe()}};
      given->table = tableFrom(b, value);
      given->vertices = vertexPositions(*b.discretizer);
      given->gridType = b.discretizer->type();
      given->grid = b.discretizer->structure();
      out.behaviors[name] = std::move(given);
    }
    for (const Behavior& b : session_->behaviors) {
      if (!out.behaviors.count(b.name)) out.behaviors[b.name] = otherTable(b);
      out.parts.push_back({b.discretizer.get(), &out.behaviors[b.name]->table, b.weight, b.activation});
    }
    return out;
  }

  py::object evaluate(const py::object& tables, std::size_t trials, std::uint64_t seed, const std::string& controller,
                      double seconds, int horizon) {
    EvalSettings settings;
    settings.controller = {controller, horizon, 0};
    settings.trials = trials;
    settings.seconds = seconds;
    settings.seed = seed;
    settings.trialsField = "trials";
    settings.secondsField = "seconds";
    checkEvalSettings(settings, {"controller", "horizon", "horizon_seconds"});
    Tables t;
    if (controller == "policy") t = tablesFor(tables.is_none() ? py::dict() : tables, "python");
    nlohmann::json report;
    {
      py::gil_scoped_release release;
      report = mgrl::evaluate(*session_, t.parts, settings);
    }
    return py::module_::import("json").attr("loads")(report.dump());
  }

  void savePolicy(const std::filesystem::path& path, const py::object& tables, const std::string& learnerName) {
    Tables t = tablesFor(tables, learnerName);
    PolicyBundle bundle;
    bundle.graphKey = session_->graph.key;
    nlohmann::json given = nlohmann::json::object();
    for (const auto& [key, value] : tables.cast<py::dict>()) given[py::str(key).cast<std::string>()] = learnerName;
    bundle.provenance = {{"scenario", session_->scenario.path.string()},
                         {"scenario_name", session_->scenario.name},
                         {"tool", fmt::format("mgrl {} (Python)", kVersion)},
                         {"sets", session_->options.sets},
                         {"python_learners", given}};
    for (const auto& [name, table] : t.behaviors) bundle.behaviors[name] = *table;
    py::gil_scoped_release release;
    savePolicyBundle(path, bundle);
  }

  // A QTable as (A, V): Q[a, v] with a the model's action index.
  py::array_t<float> tableArray(const QTable& q) const {
    const StateActionModel& model = session_->model();
    const std::size_t A = model.actionCount(), V = q.vertexCount();
    py::array_t<float> out({A, V});
    float* o = out.mutable_data();
    for (std::size_t s = 0; s < model.stateCount(); ++s) {
      const std::size_t first = model.stateActionBegin[s], n = q.actionsOf(s);
      for (std::size_t v = 0; v < V; ++v) {
        const float* row = q.row(s, v);
        for (std::size_t j = 0; j < n; ++j) o[(first + j) * V + v] = row[j];
      }
    }
    return out;
  }

 private:
  std::unique_ptr<Session> session_;
  std::unique_ptr<PolicyBundle> bundle_;  ///< the scenario's trained bundle, once read
  std::map<std::string, std::shared_ptr<PolicyBehavior>> others_;  ///< otherTable()'s, by behaviour
  nlohmann::json lastTrain_;  ///< train()'s figures, for compare
};

// Episodes of one behaviour for MotionGraphEnv (python/mgrl/env.py): single steps return
// fresh arrays (a learner may keep them), the vectorised step fills N rows in one call.
class PyEpisodes {
 public:
  PyEpisodes(py::object session, const std::string& behavior, std::size_t count, double seconds, bool endOnSuccess)
      : owner_(std::move(session)) {
    const PySession& s = owner_.cast<const PySession&>();
    const Behavior& b = s.behavior(behavior);
    episodes_ = std::make_unique<Episodes>(s.session().model(), b, count, EpisodeOptions{seconds, endOnSuccess});
  }

  std::size_t count() const { return episodes_->count(); }
  std::size_t maxActions() const { return episodes_->maxActions(); }
  int dimension() const { return episodes_->dimension(); }
  std::size_t states() const { return episodes_->model().stateCount(); }
  // Per coordinate (lowest, highest) of the grid's vertices (an angle: its whole turn).
  py::array_t<double> bounds() const {
    const auto& axes = episodes_->behavior().discretizer->axes();
    py::array_t<double> out({axes.size(), std::size_t{2}});
    for (std::size_t k = 0; k < axes.size(); ++k) {  // a wrapping axis covers its whole turn
      out.mutable_at(k, 0) = axes[k].vertices.front();
      out.mutable_at(k, 1) = axes[k].wraps ? axes[k].vertices.front() + 2 * M_PI : axes[k].vertices.back();
    }
    return out;
  }
  // The largest ground distance of a grid vertex from the avatar, m.
  double reach() const {
    const Discretizer& grid = *episodes_->behavior().discretizer;
    double r = 0;
    for (std::size_t v = 0; v < grid.vertexCount(); ++v) {
      const Eigen::Vector3d p = grid.vertexPosition(v);
      r = std::max(r, std::hypot(p.x(), p.z()));
    }
    return r;
  }
  std::vector<std::string> axisNames() const {
    std::vector<std::string> names;
    for (const GridAxis& a : episodes_->behavior().discretizer->axes()) names.push_back(a.name);
    return names;
  }

  void check(std::size_t i) const {
    if (i >= count()) throw Error(fmt::format("env: expected an index in [0, {}), found {}", count(), i));
  }

  // (state, position (3,), coordinates (D,), mask (maxActions,) bool) of slot i, fresh arrays.
  py::tuple observe(std::size_t i) const {
    check(i);
    std::int32_t state = 0;
    py::array_t<float> position(3), coordinates(dimension());
    py::array_t<bool> mask(static_cast<py::ssize_t>(maxActions()));
    episodes_->observe(i, &state, position.mutable_data(), coordinates.mutable_data(),
                       reinterpret_cast<std::uint8_t*>(mask.mutable_data()));
    return py::make_tuple(state, position, coordinates, mask);
  }

  void reset(std::size_t i, const py::object& seed) {
    check(i);
    episodes_->reset(i, seed.is_none() ? std::nullopt : std::optional<std::uint64_t>(seed.cast<std::uint64_t>()));
  }

  // One step of slot i: (reward, terminated, truncated, success, seconds played).
  py::tuple step(std::size_t i, std::int64_t choice) {
    check(i);
    if (choice < 0)
      throw Error(fmt::format("action: expected an index into state {}'s {} out-actions (info['action_mask']), found {}",
                              episodes_->state(i), episodes_->actionsAt(i), choice));
    const EpisodeStep r = episodes_->step(i, static_cast<std::size_t>(choice));
    return py::make_tuple(r.reward, r.terminated, r.truncated, r.success, episodes_->seconds(i));
  }

  // Every slot reset (slot i seeded with seed + i when a seed is given).
  void resetAll(const py::object& seed) {
    for (std::size_t i = 0; i < count(); ++i)
      episodes_->reset(i, seed.is_none() ? std::nullopt : std::optional<std::uint64_t>(seed.cast<std::uint64_t>() + i));
  }

  // Observations of every slot as (state (N,), position (N, 3), coordinates (N, D), mask (N, maxActions)).
  py::tuple observeAll() const {
    const std::size_t N = count(), D = static_cast<std::size_t>(dimension()), M = maxActions();
    py::array_t<std::int32_t> state(static_cast<py::ssize_t>(N));
    py::array_t<float> position({N, std::size_t{3}}), coordinates({N, D});
    py::array_t<bool> mask({N, M});
    std::int32_t* st = state.mutable_data();
    float* p = position.mutable_data();
    float* c = coordinates.mutable_data();
    auto* m = reinterpret_cast<std::uint8_t*>(mask.mutable_data());
    {
      py::gil_scoped_release release;
      for (std::size_t i = 0; i < N; ++i) episodes_->observe(i, st + i, p + 3 * i, c + D * i, m + M * i);
    }
    return py::make_tuple(state, position, coordinates, mask);
  }

  // Steps every slot: actions int (N,); returns (reward (N,), terminated, truncated, success).
  py::tuple stepAll(const py::object& actions) {
    const std::size_t N = count();
    if (!py::isinstance<py::array>(actions) && !py::isinstance<py::sequence>(actions))
      throw Error(fmt::format("actions: expected an integer array of shape ({},), found an object of type {}", N,
                              typeName(actions)));
    const auto given = py::array::ensure(actions);
    if (!given || given.ndim() != 1 || static_cast<std::size_t>(given.shape(0)) != N)
      throw Error(fmt::format("actions: expected an integer array of shape ({},), found shape {}", N,
                              given ? shapeText(given) : std::string("none")));
    if (given.dtype().kind() != 'i' && given.dtype().kind() != 'u')
      throw Error(fmt::format("actions: expected integers, found dtype {}", py::str(given.dtype()).cast<std::string>()));
    const auto choices = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(given);
    py::array_t<float> reward(static_cast<py::ssize_t>(N));
    py::array_t<bool> terminated(static_cast<py::ssize_t>(N)), truncated(static_cast<py::ssize_t>(N)),
        success(static_cast<py::ssize_t>(N));
    steps_.resize(N);
    {
      py::gil_scoped_release release;
      episodes_->stepAll(choices.data(), steps_.data());
    }
    float* r = reward.mutable_data();
    bool* te = terminated.mutable_data();
    bool* tr = truncated.mutable_data();
    bool* su = success.mutable_data();
    for (std::size_t i = 0; i < N; ++i) {
      r[i] = steps_[i].reward;
      te[i] = steps_[i].terminated;
      tr[i] = steps_[i].truncated;
      su[i] = steps_[i].success;
    }
    return py::make_tuple(reward, terminated, truncated, success);
  }

 private:
  py::object owner_;  // the session, kept alive
  std::unique_ptr<Episodes> episodes_;
  std::vector<EpisodeStep> steps_;
};

// The graph's arrays (python/mgrl/__init__.py lists them) as read-only views of the
// session's memory: no copy, kept alive by the session object `self`.
py::dict graphArrays(py::object self) {
  const StateActionModel& g = self.cast<const PySession&>().session().model();
  auto n = [](std::size_t size) { return static_cast<py::ssize_t>(size); };
  py::dict d;
  d["frame_time"] = g.frameTime;
  d["states"] = g.stateCount();
  d["actions"] = g.actionCount();
  d["state_frame"] = view(g.stateFrame.data(), {n(g.stateCount())}, self);
  d["state_action_begin"] = view(g.stateActionBegin.data(), {n(g.stateActionBegin.size())}, self);
  d["action_from"] = view(g.actionFrom.data(), {n(g.actionCount())}, self);
  d["action_to"] = view(g.actionTo.data(), {n(g.actionCount())}, self);
  d["action_frame_begin"] = view(g.actionFrameBegin.data(), {n(g.actionFrameBegin.size())}, self);
  d["action_frames"] = view(g.actionFrames.data(), {n(g.actionFrames.size())}, self);
  d["action_displacement"] = view(g.actionDisplacement.data(), {n(g.actionCount()), 3}, self);
  d["frame_root"] = view(g.frameRoot.data(), {n(g.frameRoot.size() / 3), 3}, self);
  d["hits"] = view(g.hits.data(), {n(g.hits.size())}, self);
  d["action_hit_begin"] = view(g.actionHitBegin.data(), {n(g.actionHitBegin.size())}, self);
  d["kicks"] = view(g.kicks.data(), {n(g.kicks.size())}, self);
  d["action_kick_begin"] = view(g.actionKickBegin.data(), {n(g.actionKickBegin.size())}, self);
  // Every source frame's joint positions (root frame, m), as the graph keeps them for hits
  // and contacts: (frames, joints, 3).
  const std::size_t joints = g.jointNames.size();
  d["joint_names"] = g.jointNames;
  if (joints > 0)
    d["joint_positions"] = view(g.sourceJoint.data(), {n(g.sourceJoint.size() / (3 * joints)), n(joints), 3}, self);
  return d;
}

}  // namespace
}  // namespace mgrl::python

PYBIND11_MODULE(_core, m) {
  using namespace mgrl::python;
  m.doc() = "mgrl's C++ core: sessions, tabulated problems and learners (import mgrl, not this)";
  PYBIND11_NUMPY_DTYPE(mgrl::ActionHit, action, offset, hand, x, y, z, weight);
  static py::exception<mgrl::Error> error(m, "Error");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mgrl::Error& e) {
      error(e.what());
    }
  });

  py::class_<ProblemArrays>(m, "Problem")
      .def_readonly("behavior", &ProblemArrays::behavior)
      .def_readonly("rewards", &ProblemArrays::rewards)
      .def_readonly("corners", &ProblemArrays::corners)
      .def_readonly("weights", &ProblemArrays::weights)
      .def_readonly("discount", &ProblemArrays::discount)
      .def_readonly("next_state", &ProblemArrays::nextState)
      .def_property_readonly("out_actions",
                             [](const ProblemArrays& p) { return py::make_tuple(p.outIndptr, p.outIndices); })
      .def_readonly("vertices", &ProblemArrays::vertices)
      .def_readonly("states", &ProblemArrays::states)
      .def_readonly("actions", &ProblemArrays::actions)
      .def_readonly("dimension", &ProblemArrays::dimension)
      .def_readonly("tabulate_seconds", &ProblemArrays::tabulateSeconds)
      .def_readonly("arrays_seconds", &ProblemArrays::arraysSeconds)
      .def_property_readonly("vertex_count", [](const ProblemArrays& p) { return p.vertexCount; });

  py::class_<PySession>(m, "Session")
      .def(py::init<const std::filesystem::path&, const py::object&, const py::object&, const py::object&>(),
           py::arg("scenario"), py::arg("data") = py::none(), py::arg("cache") = py::none(),
           py::arg("sets") = py::none())
      .def_property_readonly("behaviors", &PySession::behaviorNames)
      .def_property_readonly("scenario", [](const PySession& s) { return s.session().scenario.path; })
      .def_property_readonly("graph", &graphArrays)
      .def("problem", &PySession::problem, py::arg("behavior"))
      .def("train", &PySession::train, py::arg("behavior"), py::arg("learner") = py::none(), py::arg("sets") = py::none(),
           py::arg("progress") = py::none(), py::arg("snapshots") = 0, py::arg("on_snapshot") = py::none())
      .def_property_readonly("last_train", &PySession::lastTrain)
      .def("compare_tables", &PySession::compareTables, py::arg("behavior"), py::arg("table"), py::arg("reference"))
      .def("evaluate", &PySession::evaluate, py::arg("tables") = py::none(), py::arg("trials") = 300,
           py::arg("seed") = 1, py::arg("controller") = "policy", py::arg("seconds") = 10.0, py::arg("horizon") = 3)
      .def("save_policy", &PySession::savePolicy, py::arg("path"), py::arg("tables"), py::arg("learner") = "python");

  m.def(
      "write_compare_report",
      [](const std::filesystem::path& dir, const std::string& report) {
        mgrl::writeCompareReport(dir, nlohmann::json::parse(report));
      },
      py::arg("dir"), py::arg("report_json"), "Writes mgrl compare's results.json, results.csv, curves.csv, index.html");
  m.def("compare_metrics", [] { return mgrl::compareMetrics(); });
  m.def(
      "learner_parameters",
      [](const std::string& name) {
        const auto* entry = mgrl::builtinPlugins().learners.find(name);
        if (!entry)
          throw mgrl::Error(fmt::format("learners: expected a registered learner ({}), found '{}'",
                                        mgrl::builtinPlugins().learners.describeKnown(), name));
        std::vector<std::string> names;
        for (const auto& p : entry->params) names.push_back(p.name);
        return names;
      },
      py::arg("name"), "The parameter names of a registered C++ learner");
  m.def("snapshot_columns", [] { return mgrl::snapshotColumns(); });

  py::class_<PyEpisodes>(m, "Episodes")
      .def(py::init<py::object, const std::string&, std::size_t, double, bool>(), py::arg("session"),
           py::arg("behavior"), py::arg("count") = 1, py::arg("seconds") = 10.0, py::arg("end_on_success") = false)
      .def_property_readonly("count", &PyEpisodes::count)
      .def_property_readonly("max_actions", &PyEpisodes::maxActions)
      .def_property_readonly("dimension", &PyEpisodes::dimension)
      .def_property_readonly("states", &PyEpisodes::states)
      .def_property_readonly("bounds", &PyEpisodes::bounds)
      .def_property_readonly("axes", &PyEpisodes::axisNames)
      .def_property_readonly("reach", &PyEpisodes::reach)
      .def("observe", &PyEpisodes::observe, py::arg("i"))
      .def("reset", &PyEpisodes::reset, py::arg("i"), py::arg("seed") = py::none())
      .def("step", &PyEpisodes::step, py::arg("i"), py::arg("choice"))
      .def("observe_all", &PyEpisodes::observeAll)
      .def("reset_all", &PyEpisodes::resetAll, py::arg("seed") = py::none())
      .def("step_all", &PyEpisodes::stepAll, py::arg("actions"));
}
