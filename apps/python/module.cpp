// PYBIND11_MODULE(_uavsim): the version, the error translation and the
// bindings of each part (bindings.h).
#include <pybind11/pybind11.h>

#include "apps/python/bindings.h"
#include "core/error.h"
#include "core/interrupt.h"
#include "pipeline/edge/scripted_edge.h"
#include "sim/version.h"

namespace py = pybind11;
using namespace uavsim;

namespace {

// C++ text as Python's. Bytes that are not UTF-8 become U+FFFD: a strict
// decoding would raise UnicodeDecodeError in place of the error.
py::str Text(const std::string& s) {
  PyObject* text = PyUnicode_DecodeUTF8(s.data(), static_cast<Py_ssize_t>(s.size()), "replace");
  if (!text) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(text);
}

// The message as the error's line shows it (one line of UTF-8, control
// characters and bytes that are not UTF-8 escaped: core/error.cpp), so that
// it is part of str(e): the line past that of the same error without one.
std::string ShownMessage(const core::ConfigError& e) {
  const core::ConfigError bare = e.about_document() ? core::ConfigError::AboutDocument(e.file(), "")
                                                    : core::ConfigError(e.file(), e.pointer(), "");
  const std::string line = e.what(), prefix = bare.what();
  return line.compare(0, prefix.size(), prefix) == 0 ? line.substr(prefix.size()) : e.message();
}

// Sets uavsim.ScenarioError(line, file, pointer, message) (uavsim/_errors.py).
void SetScenarioError(py::object file, py::object pointer, const std::string& message,
                      const std::string& line) {
  const py::object cls = py::module_::import("uavsim._errors").attr("ScenarioError");
  const py::object error = cls(Text(line), file, pointer, Text(message));
  PyErr_SetObject(cls.ptr(), error.ptr());
}

void Translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const core::ConfigError& e) {
    SetScenarioError(Text(e.file()), Text(e.pointer()), ShownMessage(e), e.what());
  } catch (const core::UsageError& e) {
    SetScenarioError(py::none(), py::none(), e.what(), e.what());
  } catch (const core::Interrupted&) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
  } catch (const pipeline::ScriptedEdgeFailure& e) {
    PyErr_SetString(PyExc_RuntimeError, (std::string(e.what()) + "\n" + e.traceback()).c_str());
  }
}

}  // namespace

PYBIND11_MODULE(_uavsim, m) {
  m.doc() = "uavsim's engine (the package uavsim is the interface)";
  m.attr("__version__") = sim::Version();
  m.attr("git_hash") = sim::GitHash();
  py::register_exception_translator(Translate);
  python::BindScenario(m);
  python::BindRun(m);
  python::BindEnvironment(m);
}
