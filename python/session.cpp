// mgrl.Session's graph views and its registration with the module (session.hpp).
#include "session.hpp"

#include "docstrings.hpp"

#include "mgrl/core/data_paths.hpp"
#include "mgrl/motion/capture_report.hpp"
#include "mgrl/runtime/bout_report.hpp"

namespace mgrl::python {
namespace {

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

void bindSession(py::module_& m) {
  using P = ProblemArrays;
  py::class_<P> problem(m, "Problem", doc::kProblemClass);
  bindReadonly(problem, Readonly{"behavior", &P::behavior, doc::kBehavior},
               Readonly{"rewards", &P::rewards, doc::kRewards}, Readonly{"corners", &P::corners, doc::kCorners},
               Readonly{"weights", &P::weights, doc::kWeights}, Readonly{"discount", &P::discount, doc::kDiscount},
               Readonly{"next_state", &P::nextState, doc::kNextState},
               Readonly{"vertices", &P::vertices, doc::kVertices}, Readonly{"states", &P::states, doc::kStates},
               Readonly{"actions", &P::actions, doc::kActions}, Readonly{"dimension", &P::dimension, doc::kDimension},
               Readonly{"tabulate_seconds", &P::tabulateSeconds, doc::kTabulateSeconds},
               Readonly{"arrays_seconds", &P::arraysSeconds, doc::kArraysSeconds},
               Readonly{"vertex_count", &P::vertexCount, doc::kVertexCount});
  problem.def_property_readonly(
      "out_actions", [](const P& p) { return py::make_tuple(p.outIndptr, p.outIndices); }, doc::kOutActions);

  py::class_<PySession>(m, "Session", doc::kSession)
      .def(py::init<const std::filesystem::path&, const py::object&, const py::object&, const py::object&,
                    const py::object&>(),
           py::arg("scenario"), py::arg("data") = py::none(), py::arg("cache") = py::none(),
           py::arg("sets") = py::none(), py::arg("policy") = py::none())
      .def_property_readonly("behaviors", &PySession::behaviorNames, doc::kBehaviors)
      .def_property_readonly(
          "scenario", [](const PySession& s) { return s.session().scenario.path; }, doc::kScenario)
      .def_property_readonly("graph", &graphArrays, doc::kGraph)
      .def("problem", &PySession::problem, py::arg("behavior"), doc::kProblem)
      .def("train", &PySession::train, py::arg("behavior"), py::arg("learner") = py::none(),
           py::arg("sets") = py::none(), py::arg("progress") = py::none(), py::arg("snapshots") = 0,
           py::arg("on_snapshot") = py::none(), doc::kTrain)
      .def_property_readonly("last_train", &PySession::lastTrain, doc::kLastTrain)
      .def("compare_tables", &PySession::compareTables, py::arg("behavior"), py::arg("table"), py::arg("reference"),
           doc::kCompareTables)
      .def("evaluate", &PySession::evaluate, py::arg("tables") = py::none(), py::arg("trials") = 300,
           py::arg("seed") = 1, py::arg("controller") = "policy", py::arg("seconds") = 10.0, py::arg("horizon") = 3,
           py::arg("train_missing") = false, doc::kEvaluate)
      .def("simulate", &PySession::simulate, py::arg("tables") = py::none(), py::arg("avatars") = 2,
           py::arg("seconds") = 10.0, py::arg("seed") = 1, py::arg("controller") = "policy", py::arg("horizon") = 3,
           py::arg("bvh_out") = py::none(), py::arg("gltf_out") = py::none(), py::arg("events_out") = py::none(),
           py::arg("poses") = false, py::arg("train_missing") = false, doc::kSimulate)
      .def("save_policy", &PySession::savePolicy, py::arg("path"), py::arg("tables"), py::arg("learner") = "python",
           py::arg("train_missing") = false, doc::kSavePolicy)
      .def("load_policy", &PySession::loadPolicy, py::arg("path"), doc::kLoadPolicy);

  m.def(
      "write_compare_report",
      [](const std::filesystem::path& dir, const std::string& report) {
        mgrl::writeCompareReport(dir, nlohmann::json::parse(report));
      },
      py::arg("dir"), py::arg("report_json"), "Writes mgrl compare's results.json, results.csv, curves.csv, index.html");
  m.def("compare_metrics", [] { return mgrl::compareMetrics(); });
  m.def(
      "learner_summaries",
      [](const std::string& runs, const std::vector<std::string>& learners) {
        return mgrl::learnerSummaries(nlohmann::json::parse(runs), learners).dump();
      },
      py::arg("runs_json"), py::arg("learners"),
      "mgrl compare's per-learner mean, sd and success curve over the runs, as JSON text");
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
  m.def(
      "_bout_stats",
      [](const std::vector<std::string>& bouts, bool snu, const std::vector<std::string>& against,
         const py::object& data) {
        mgrl::StatsOptions options;
        options.bouts = bouts;
        options.snu = snu;
        options.compare = !against.empty();
        options.synthetic = against;
        options.dataDir =
            mgrl::dataDirectory(data.is_none() ? std::filesystem::path() : data.cast<std::filesystem::path>());
        std::vector<std::string> warnings;
        options.warn = [&](const std::string& line) { warnings.push_back(line); };
        return nlohmann::json{{"report", mgrl::runStats(options)}, {"warnings", warnings}}.dump();
      },
      py::arg("bouts"), py::arg("snu"), py::arg("against"), py::arg("data"),
      "mgrl stats --json's report and the warnings, as JSON text (mgrl.bout_stats parses it)");
  m.def(
      "_inspect",
      [](const std::vector<std::filesystem::path>& files) {
        mgrl::InspectOptions options;
        std::vector<std::string> warnings;
        options.load.warn = [&](const std::string& line) { warnings.push_back(line); };
        options.annotation.validate();
        std::vector<mgrl::FileReport> reports;  // every file read before any is reported
        reports.reserve(files.size());
        for (const std::filesystem::path& file : files) reports.push_back(mgrl::inspectFile(file, options));
        return nlohmann::json{{"report", mgrl::inspectJson(reports)}, {"warnings", warnings}}.dump();
      },
      py::arg("files"), "mgrl inspect --json's report and the warnings, as JSON text (mgrl.inspect parses it)");
}

}  // namespace mgrl::python
