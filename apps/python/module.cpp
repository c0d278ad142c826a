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

// Sets uavsim.ScenarioError(line, file, pointer, message) (uavsim/_errors.py).
void SetScenarioError(py::object file, py::object pointer, const std::string& message,
                      const std::string& line) {
  const py::object cls = py::module_::import("uavsim._errors").attr("ScenarioError");
  const py::object error = cls(line, file, pointer, message);
  PyErr_SetObject(cls.ptr(), error.ptr());
}

void Translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const core::ConfigError& e) {
    SetScenarioError(py::str(e.file()), py::str(e.pointer()), e.message(), e.what());
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
