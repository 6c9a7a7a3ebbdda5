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
#include <memory>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/config.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/problem.hpp"
#include "mgrl/session/plugins.hpp"
#include "mgrl/session/session.hpp"

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

// The tabulated problem of one behaviour as NumPy arrays (python/mgrl/__init__.py,
// Problem): what value iteration backs up, corner by corner.
struct ProblemArrays {
  std::string behavior;
  py::array_t<float> rewards, weights, discount;
  py::array_t<std::int32_t> corners, nextState, outIndptr, outIndices;
  py::array_t<double> vertices;
  std::size_t states = 0, actions = 0, vertexCount = 0;
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
    if (grid.layerAxis() || !grid.hanging().empty())
      throw Error(fmt::format("problem({}): its grid ({}) has {}; only plain product grids are offered to Python yet",
                              name, grid.type(), grid.layerAxis() ? "speed layers" : "hanging vertices"));
    const StateActionModel& model = session_->model();
    const Problem problem = b.problem(model);
    GridModel g;
    {
      py::gil_scoped_release release;
      g = GridModel::build(problem, std::max(1u, std::thread::hardware_concurrency()));
    }
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
    for (std::size_t a = 0; a < A; ++a)
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
    p.discount = py::array_t<float>(A);
    std::copy(g.discount.begin(), g.discount.end(), p.discount.mutable_data());
    p.nextState = py::array_t<std::int32_t>(A);
    std::copy(g.actionTo.begin(), g.actionTo.end(), p.nextState.mutable_data());
    p.outIndptr = py::array_t<std::int32_t>(model.stateCount() + 1);
    std::copy(model.stateActionBegin.begin(), model.stateActionBegin.end(), p.outIndptr.mutable_data());
    // The model numbers each state's out-actions contiguously: indices are 0 .. A-1.
    p.outIndices = py::array_t<std::int32_t>(A);
    for (std::size_t a = 0; a < A; ++a) p.outIndices.mutable_data()[a] = static_cast<std::int32_t>(a);
    // Each vertex as the grid's coordinates (angle, distance, height, ... as its axes say).
    const int D = grid.dimension();
    p.vertices = py::array_t<double>({V, static_cast<std::size_t>(D)});
    for (std::size_t v = 0; v < V; ++v) {
      const auto coordinates = grid.coordinates(grid.vertexState(v));
      for (int d = 0; d < D; ++d) p.vertices.mutable_data()[v * D + d] = coordinates[static_cast<std::size_t>(d)];
    }
    return p;
  }

  // Any registered learner on one behaviour; the table as (A, V) float32.
  py::array_t<float> train(const std::string& name, const py::object& learner, const py::object& sets) {
    const Behavior& b = behavior(name);
    const StateActionModel& model = session_->model();
    nlohmann::json config = b.config.value("learner", nlohmann::json::object());
    if (!learner.is_none()) config = {{"type", learner.cast<std::string>()}};
    for (const std::string& set : setsOf(sets)) {
      const std::size_t eq = set.find('=');
      if (eq == std::string::npos) throw Error(fmt::format("sets: expected 'key=value', found '{}'", set));
      config[set.substr(0, eq)] = nlohmann::json::parse(set.substr(eq + 1), nullptr, false).is_discarded()
                                      ? nlohmann::json(set.substr(eq + 1))
                                      : nlohmann::json::parse(set.substr(eq + 1));
    }
    const auto made = builtinPlugins().learners.create(ConfigNode::parse(config.dump(), fmt::format("{} learner", name)));
    made->checkGrid(*b.discretizer);
    const Problem problem = b.problem(model);
    TrainResult result;
    {
      py::gil_scoped_release release;
      const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
      const GridModel g = made->takesCompactModel() ? GridModel::buildCompact(problem, threads)
                                                   : GridModel::build(problem, threads);
      result = made->train({problem, g, nullptr, nullptr, threads, nullptr});
    }
    if (result.grid)
      throw Error(fmt::format("train: the learner {} refined its own grid ({} vertices); tables on refined grids are "
                              "not offered to Python yet",
                              made->type(), result.table.vertexCount()));
    return tableArray(result.table);
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
};

}  // namespace
}  // namespace mgrl::python

PYBIND11_MODULE(_core, m) {
  using namespace mgrl::python;
  m.doc() = "mgrl's C++ core: sessions, tabulated problems and learners (import mgrl, not this)";
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
      .def_property_readonly("vertex_count", [](const ProblemArrays& p) { return p.vertexCount; });

  py::class_<PySession>(m, "Session")
      .def(py::init<const std::filesystem::path&, const py::object&, const py::object&, const py::object&>(),
           py::arg("scenario"), py::arg("data") = py::none(), py::arg("cache") = py::none(),
           py::arg("sets") = py::none())
      .def_property_readonly("behaviors", &PySession::behaviorNames)
      .def_property_readonly("scenario", [](const PySession& s) { return s.session().scenario.path; })
      .def_property_readonly("graph",
                             [](py::object self) {
                               const mgrl::StateActionModel& m = self.cast<const PySession&>().session().model();
                               py::dict d;
                               d["action_from"] = view(m.actionFrom.data(), {static_cast<py::ssize_t>(m.actionCount())}, self);
                               d["action_to"] = view(m.actionTo.data(), {static_cast<py::ssize_t>(m.actionCount())}, self);
                               d["action_frame_begin"] =
                                   view(m.actionFrameBegin.data(), {static_cast<py::ssize_t>(m.actionFrameBegin.size())}, self);
                               d["action_displacement"] =
                                   view(m.actionDisplacement.data(), {static_cast<py::ssize_t>(m.actionCount()), 3}, self);
                               d["state_frame"] = view(m.stateFrame.data(), {static_cast<py::ssize_t>(m.stateCount())}, self);
                               d["state_action_begin"] = view(m.stateActionBegin.data(),
                                                              {static_cast<py::ssize_t>(m.stateActionBegin.size())}, self);
                               d["frame_time"] = m.frameTime;
                               return d;
                             })
      .def("problem", &PySession::problem, py::arg("behavior"))
      .def("train", &PySession::train, py::arg("behavior"), py::arg("learner") = py::none(), py::arg("sets") = py::none());
}
