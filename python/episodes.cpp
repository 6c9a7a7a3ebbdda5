// Episodes of one behaviour for MotionGraphEnv (python/mgrl/env.py) and its registration.
#include <limits>

#include "session.hpp"

namespace mgrl::python {
namespace {

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
  // Per coordinate (lowest, highest) of the values an observation's coordinates can take,
  // the grid's edge and beyond (a terminal observation's target has left the grid, a placed
  // one may start outside it): angles their whole turn, a distance from 0, a height
  // unbounded; layer axes (speed, opponent, turn) hold their layers' values.
  py::array_t<double> domain() const {
    const auto& axes = episodes_->behavior().discretizer->axes();
    const double inf = std::numeric_limits<double>::infinity();
    py::array_t<double> out({axes.size(), std::size_t{2}});
    for (std::size_t k = 0; k < axes.size(); ++k) {
      const GridAxis& a = axes[k];
      double lo = a.vertices.front(), hi = a.wraps ? a.vertices.front() + 2 * M_PI : a.vertices.back();
      switch (a.role) {
        case AxisRole::Angle:
        case AxisRole::Heading:  // atan2's range, or the axis' own turn
          lo = std::min(lo, -M_PI);
          hi = std::max(hi, M_PI);
          break;
        case AxisRole::Distance:
          lo = 0;
          hi = inf;
          break;
        case AxisRole::Height:
          lo = -inf;
          hi = inf;
          break;
        case AxisRole::Speed:
        case AxisRole::Opponent:
        case AxisRole::Turn:
          break;
      }
      out.mutable_at(k, 0) = lo;
      out.mutable_at(k, 1) = hi;
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
    for (const GridAxis& a : episodes_->behavior().discretizer->axes()) names.emplace_back(a.name());
    return names;
  }

  void check(std::size_t i) const {
    if (i >= count()) throw Error(fmt::format("env: expected an index in [0, {}), found {}", count(), i));
  }

  // (state, position (3,), coordinates (D,), mask (maxActions,) int8: 1 where legal) of
  // slot i, fresh arrays. The mask is int8 as Gymnasium's Discrete.sample(mask=) takes it.
  py::tuple observe(std::size_t i) const {
    check(i);
    std::int32_t state = 0;
    py::array_t<float> position(3), coordinates(dimension());
    py::array_t<std::int8_t> mask(static_cast<py::ssize_t>(maxActions()));
    episodes_->observe(i, &state, position.mutable_data(), coordinates.mutable_data(),
                       reinterpret_cast<std::uint8_t*>(mask.mutable_data()));
    return py::make_tuple(state, position, coordinates, mask);
  }

  // Slot i restarted, seeded when seed is not None, at `state` and `target` when they are
  // not None (MotionGraphEnv.reset's options; Episodes::reset checks their values).
  void reset(std::size_t i, const py::object& seed, const py::object& state, const py::object& target) {
    check(i);
    episodes_->reset(i, seed.is_none() ? std::nullopt : std::optional<std::uint64_t>(seed.cast<std::uint64_t>()),
                     placement(state, target));
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

  // Every slot reset (slot i seeded with seed + i when a seed is given), each at `state` and
  // `target` when they are not None.
  void resetAll(const py::object& seed, const py::object& state, const py::object& target) {
    const EpisodeStart at = placement(state, target);
    for (std::size_t i = 0; i < count(); ++i)
      episodes_->reset(i, seed.is_none() ? std::nullopt : std::optional<std::uint64_t>(seed.cast<std::uint64_t>() + i),
                       at);
  }

  // Observations of every slot as (state (N,), position (N, 3), coordinates (N, D), mask (N, maxActions)).
  py::tuple observeAll() const {
    const std::size_t N = count(), D = static_cast<std::size_t>(dimension()), M = maxActions();
    py::array_t<std::int32_t> state(static_cast<py::ssize_t>(N));
    py::array_t<float> position({N, std::size_t{3}}), coordinates({N, D});
    py::array_t<std::int8_t> mask({N, M});
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

  // Steps every slot: actions int (N,); returns (reward (N,), terminated, truncated, success,
  // state (N,), position (N, 3), coordinates (N, D)), the last three where each step led:
  // for a slot whose episode ended, where it ended, before the slot started anew.
  py::tuple stepAll(const py::object& actions) {
    const std::size_t N = count(), D = static_cast<std::size_t>(dimension());
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
    py::array_t<std::int32_t> endState(static_cast<py::ssize_t>(N));
    py::array_t<float> endPosition({N, std::size_t{3}}), endCoordinates({N, D});
    steps_.resize(N);
    ends_.resize(N);
    {
      py::gil_scoped_release release;
      episodes_->stepAll(choices.data(), steps_.data(), ends_.data());
      for (std::size_t i = 0; i < N; ++i)  // where the episodes that go on are now
        if (!steps_[i].terminated && !steps_[i].truncated)
          episodes_->observe(i, &ends_[i].state, ends_[i].position, ends_[i].coordinates, nullptr);
    }
    float* r = reward.mutable_data();
    bool* te = terminated.mutable_data();
    bool* tr = truncated.mutable_data();
    bool* su = success.mutable_data();
    std::int32_t* es = endState.mutable_data();
    float* ep = endPosition.mutable_data();
    float* ec = endCoordinates.mutable_data();
    for (std::size_t i = 0; i < N; ++i) {
      r[i] = steps_[i].reward;
      te[i] = steps_[i].terminated;
      tr[i] = steps_[i].truncated;
      su[i] = steps_[i].success;
      es[i] = ends_[i].state;
      std::copy_n(ends_[i].position, 3, ep + 3 * i);
      std::copy_n(ends_[i].coordinates, D, ec + D * i);
    }
    return py::make_tuple(reward, terminated, truncated, success, endState, endPosition, endCoordinates);
  }

 private:
  // The start reset() places from Python's values: the state an integer (a Python or NumPy
  // one, not a bool), the target 3 real numbers; their ranges are Episodes::reset's to check.
  EpisodeStart placement(const py::object& state, const py::object& target) const {
    EpisodeStart at;
    if (!state.is_none()) {
      const std::string expected = fmt::format("options['state']: expected a graph state in [0, {}), found ", states());
      if (PyBool_Check(state.ptr()) || !PyIndex_Check(state.ptr()))
        throw Error(expected + fmt::format("{} of type {}", py::repr(state).cast<std::string>(), typeName(state)));
      int overflow = 0;
      const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(state.ptr()));
      if (!index) throw py::error_already_set();
      const long long value = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
      if (overflow) throw Error(expected + py::repr(state).cast<std::string>());
      at.state = value;
    }
    if (!target.is_none()) {
      const char* expected =
          "options['target']: expected 3 numbers (x, y, z in metres, the avatar's frame, as obs['target'])";
      if (!py::isinstance<py::array>(target) && !py::isinstance<py::sequence>(target))
        throw Error(fmt::format("{}, found an object of type {}", expected, typeName(target)));
      const auto given = py::array::ensure(target);
      if (!given || given.ndim() != 1 || given.shape(0) != 3)
        throw Error(fmt::format("{}, found shape {}", expected, given ? shapeText(given) : std::string("none")));
      const char kind = given.dtype().kind();
      if (kind != 'f' && kind != 'i' && kind != 'u')
        throw Error(fmt::format("{}, found dtype {}", expected, py::str(given.dtype()).cast<std::string>()));
      const auto xyz = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
      at.target = Eigen::Vector3d(xyz.at(0), xyz.at(1), xyz.at(2));
    }
    return at;
  }

  py::object owner_;  // the session, kept alive
  std::unique_ptr<Episodes> episodes_;
  std::vector<EpisodeStep> steps_;
  std::vector<EpisodeEnd> ends_;
};

}  // namespace

void bindEpisodes(py::module_& m) {
  using E = PyEpisodes;
  py::class_<E> episodes(m, "Episodes");
  episodes.def(py::init<py::object, const std::string&, std::size_t, double, bool>(), py::arg("session"),
               py::arg("behavior"), py::arg("count") = 1, py::arg("seconds") = 10.0, py::arg("end_on_success") = false);
  bindReadonly(episodes, Readonly{"count", &E::count}, Readonly{"max_actions", &E::maxActions},
               Readonly{"dimension", &E::dimension}, Readonly{"states", &E::states}, Readonly{"bounds", &E::bounds},
               Readonly{"domain", &E::domain}, Readonly{"axes", &E::axisNames}, Readonly{"reach", &E::reach});
  episodes.def("observe", &E::observe, py::arg("i"))
      .def("reset", &E::reset, py::arg("i"), py::arg("seed") = py::none(), py::arg("state") = py::none(),
           py::arg("target") = py::none())
      .def("step", &E::step, py::arg("i"), py::arg("choice"))
      .def("observe_all", &E::observeAll)
      .def("reset_all", &E::resetAll, py::arg("seed") = py::none(), py::arg("state") = py::none(),
           py::arg("target") = py::none())
      .def("step_all", &E::stepAll, py::arg("actions"));
}

}  // namespace mgrl::python
