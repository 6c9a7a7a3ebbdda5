#pragma once
// mgrl.Session (python/mgrl/__init__.py): a session (framework/session) with its problems,
// C++ training, eval's trials and policy bundles for NumPy tables.
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

#include "builtin_plugins.hpp"
#include "mgrl/core/config.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/reports/compare_report.hpp"
#include "mgrl/session/compare_summary.hpp"
#include "mgrl/session/compare_tables.hpp"
#include "mgrl/session/episodes.hpp"
#include "mgrl/session/evaluate.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/simulate.hpp"
#include "mgrl/session/training.hpp"
#include "support.hpp"
#include "train_watch.hpp"

namespace mgrl::python {

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

/// `scenario` as given, or for a bare name that is no file here ("boxing", "boxing.yaml"),
/// the scenario of that name the module carries (mgrl.scenario_path); a name it does not
/// carry either is left to the session's own message.
std::filesystem::path shippedScenario(const std::filesystem::path& scenario);

/// A scenario error as Python names its cause: the command line's "--set KEY=VALUE: ..."
/// becomes "sets['KEY'] (= VALUE): ...", the override given in Session(sets=...).
std::string setsMessage(const std::string& what);

/// The learner train(learner=, sets=) asks for, made from its block `config` (the
/// scenario's, or a new one of the named type, with the sets applied). Its errors name
/// train's arguments, not a position in the block (which the user never wrote).
std::unique_ptr<Learner> learnerFrom(const nlohmann::json& config, const std::string& behavior);

class PySession {
 public:
  // `policy`: None or a policy bundle's folder (mgrl train's or save_policy's), whose tables
  // evaluate and simulate play for the behaviours they are not given.
  PySession(const std::filesystem::path& scenario, const py::object& data, const py::object& cache,
            const py::object& sets, const py::object& policy);

  const Session& session() const { return *session_; }

  std::vector<std::string> behaviorNames() const;

  const Behavior& behavior(const std::string& name) const;

  ProblemArrays problem(const std::string& name) const;

  // Any registered learner on one behaviour; the table as (A, V) float32.
  py::array_t<float> train(const std::string& name, const py::object& learner, const py::object& sets,
                           const py::object& progress, std::size_t snapshots, const py::object& onSnapshot);

  // What the last train() reported: updates, seconds, final_residual, curve, stats.
  py::object lastTrain() const {
    if (lastTrain_.is_null()) return py::none();
    return py::module_::import("json").attr("loads")(lastTrain_.dump());
  }

  // compare's table measures against a reference table on the same behaviour's grid:
  // {"value_rmse", "greedy_agreement", "reference_interpolated"} (mgrl/session/compare_tables.hpp).
  py::dict compareTables(const std::string& name, const py::object& table, const py::object& reference) const;

  // A NumPy Q table for behaviour `b`: float32 of shape (A, V) with finite values. Refused
  // otherwise with one message naming both shapes, before anything is allocated for it.
  QTable tableFrom(const Behavior& b, const py::handle& value) const;

  // A policy bundle read for this session's graph; a bundle that does not fit (another
  // graph, a damaged file) is refused naming `where` and the folder.
  PolicyBundle readBundle(const std::filesystem::path& dir, std::string_view where) const;

  // A behaviour's table for evaluate, simulate and save_policy (`where`) when they are not
  // given one: from the bundle the session was opened with (policy=), else from the
  // scenario's trained bundle when it holds a current one, else, with `trainMissing`,
  // trained here with the scenario's learner (once per session; said on stderr). Without
  // it a missing table is an error saying how to get one from Python.
  std::shared_ptr<PolicyBehavior> otherTable(const Behavior& b, bool trainMissing, std::string_view where);

  // A policy bundle's tables as {behaviour: (A, V) float32}, for this session's graph.
  py::dict loadPolicy(const std::filesystem::path& dir) const;

  // The scenario's behaviours, in its order: `tables` (a dict of NumPy arrays) for those it
  // names, otherTable() for the rest. `learnerName` goes into the given ones' records.
  struct Tables {
    std::map<std::string, std::shared_ptr<PolicyBehavior>> behaviors;
    std::vector<PolicyPart> parts;
  };
  Tables tablesFor(const py::object& tables, const std::string& learnerName, bool trainMissing, std::string_view where);

  py::object evaluate(const py::object& tables, std::size_t trials, std::uint64_t seed, const std::string& controller,
                      double seconds, int horizon, bool trainMissing);

  // The world run headless (mgrl::simulate) on `tables` (as evaluate's); exports as `mgrl
  // simulate`'s. The session was opened on the model alone; the first call opens it again
  // with the capture (poses and bodies need it) and keeps that one for the next calls. The
  // tables' grids are this session's behaviours', the same grids as the other's.
  py::object simulate(const py::object& tables, long long avatars, double seconds, std::uint64_t seed,
                      const std::string& controller, int horizon, const py::object& bvhOut, const py::object& gltfOut,
                      const py::object& eventsOut, bool poses, bool trainMissing);

  // `session` opened again with the capture; refused if the capture is no longer the one its
  // graph was made from (the tables index that graph's actions).
  static std::unique_ptr<const Session> withCapture(const Session& session);

  void savePolicy(const std::filesystem::path& path, const py::object& tables, const std::string& learnerName,
                  bool trainMissing);

  // A QTable as (A, V): Q[a, v] with a the model's action index.
  py::array_t<float> tableArray(const QTable& q) const;

 private:
  std::unique_ptr<const Session> session_;
  std::unique_ptr<const Session> captured_;  ///< the same scenario with the capture, for simulate
  std::unique_ptr<PolicyBundle> bundle_;     ///< policy='s bundle, else the scenario's trained one once read
  std::filesystem::path policyDir_;          ///< policy= (empty: the scenario's trained bundle)
  std::map<std::string, std::shared_ptr<PolicyBehavior>> others_;  ///< otherTable()'s, by behaviour
  nlohmann::json lastTrain_;                                       ///< train()'s figures, for compare
};

/// Registers Problem, Session and compare's measures and report with the module.
void bindSession(py::module_& m);

}  // namespace mgrl::python
