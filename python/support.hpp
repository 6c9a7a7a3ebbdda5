#pragma once
// Small pieces every part of mgrl._core uses: NumPy views, --set lists, type and shape
// names for messages, lines to Python's stderr.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <type_traits>
#include <vector>

namespace py = pybind11;

namespace mgrl::python {

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

// A read-only attribute of a bound class: its Python name and the C++ member behind it,
// a data member or a const member function that takes nothing.
template <class Member>
struct Readonly {
  const char* name;
  Member member;
  const char* doc = "";  ///< its docstring (python/docstrings.hpp)
};
template <class Member>
Readonly(const char*, Member) -> Readonly<Member>;  // clang 14 deduces no aggregate's arguments
template <class Member>
Readonly(const char*, Member, const char*) -> Readonly<Member>;

// Binds each of `attributes` to `cls`: data members by def_readonly (NumPy arrays stay the
// member's own), member functions as properties.
template <class Class, class... Members>
Class& bindReadonly(Class& cls, Readonly<Members>... attributes) {
  const auto bindOne = [&cls](const char* name, auto member, const char* doc) {
    if constexpr (std::is_member_object_pointer_v<decltype(member)>)
      cls.def_readonly(name, member, doc);
    else
      cls.def_property_readonly(name, member, doc);
  };
  (bindOne(attributes.name, attributes.member, attributes.doc), ...);
  return cls;
}

// `sets` as the command line takes them: a dict {key: value} or a list of "key=value".
inline std::vector<std::string> setsOf(const py::object& sets) {
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

inline std::string typeName(const py::handle& value) {
  return py::str(py::type::of(value).attr("__name__")).cast<std::string>();
}

// "(1438, 100)": a NumPy array's shape as Python prints it.
inline std::string shapeText(const py::array& a) {
  std::vector<py::ssize_t> dims(a.shape(), a.shape() + a.ndim());
  if (dims.size() == 1) return fmt::format("({},)", dims[0]);
  return fmt::format("({})", fmt::join(dims, ", "));
}

// Lines for the user (what the command line prints on stderr) go to Python's sys.stderr,
// so that notebooks show them; callable from any thread.
inline void toStderr(const std::string& line) {
  py::gil_scoped_acquire gil;
  py::module_::import("sys").attr("stderr").attr("write")(line + "\n");
}

}  // namespace mgrl::python
