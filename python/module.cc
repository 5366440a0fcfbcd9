// The Python module hovs._hovs (re-exported by the package hovs). hovs::Error becomes hovs.Error (a ValueError
// subclass) carrying hovs' message, which names the input and the problem.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <exception>
#include <string>

#include "apps/commands.h"
#include "core/error.h"
#include "python/bindings.h"

PYBIND11_MODULE(_hovs, m) {
  namespace py = pybind11;
  m.doc() = "hovs: hyperboloid catadioptric camera models, virtual views, datasets and design, from Python.";
  // The message as text even when it quotes bytes of a binary file (invalid UTF-8 is backslash-escaped).
  static py::exception<hovs::Error> error(m, "Error", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const hovs::Error& e) {
      const std::string what = e.what();
      PyObject* text = PyUnicode_DecodeUTF8(what.data(), static_cast<Py_ssize_t>(what.size()), "backslashreplace");
      PyErr_SetObject(error.ptr(), text);
      Py_XDECREF(text);
    }
  });
  m.def(
      "versions", [] { return hovs::apps::Versions(); },
      "hovs' version and every library's it was built with (what each output records).");
  hovs::python::BindCamera(m);
  hovs::python::BindUnwrap(m);
  hovs::python::BindDataset(m);
  hovs::python::BindStudy(m);
  hovs::python::BindCalibration(m);
}
