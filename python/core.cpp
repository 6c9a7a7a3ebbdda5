// mgrl._core: the session stage (framework/session) bound to Python with pybind11.
// The package mgrl (python/mgrl/__init__.py) re-exports what users call. Arrays are NumPy
// views of the session's own memory where they can be (the graph's), else arrays made once.
// The parts: support.hpp (helpers), train_watch (training from Python), session (Session,
// Problem, compare's measures), episodes (the environments).
#include <pybind11/pybind11.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/graph/state_action_model.hpp"
#include "session.hpp"

namespace mgrl::python {
void bindEpisodes(py::module_& m);
}  // namespace mgrl::python

PYBIND11_MODULE(_core, m) {
  using namespace mgrl::python;
  m.doc() = "mgrl's C++ core: sessions, tabulated problems and learners (import mgrl, not this)";
  m.attr("__version__") = mgrl::kVersion;
  PYBIND11_NUMPY_DTYPE(mgrl::ActionHit, action, offset, hand, x, y, z, weight);
  static py::exception<mgrl::Error> error(m, "Error");
  // Printed and pickled as mgrl.Error, the name users import it by, not the extension's.
  error.attr("__module__") = "mgrl";
  error.attr("__doc__") =
      "What mgrl refuses: bad input (a scenario, a table's shape, an option) or a state it cannot reach, "
      "with a message that says where, what was expected and what was found.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mgrl::Error& e) {
      error(e.what());
    }
  });

  bindSession(m);
  bindEpisodes(m);
}
