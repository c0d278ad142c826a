// The Python module `uavsim._uavsim` (issue 45): what the package
// uavsim/ (apps/python/uavsim) is built on. Scenarios cross as JSON text,
// results as the run directory's files; the package turns them into dicts
// and NumPy arrays. Errors: core::ConfigError and core::UsageError become
// uavsim.ScenarioError (file, pointer, message: the command line's line),
// an interrupt KeyboardInterrupt, a Python method's exception itself.
#pragma once

#include <pybind11/pybind11.h>

#include <functional>
#include <string>
#include <vector>

#include "sim/hosted_method.h"
#include "sim/scenario.h"

namespace uavsim::python {

namespace py = pybind11;

// A scenario as Python holds it: a file (path) or a document (JSON text,
// relative paths from the working directory), and --set overrides.
struct ScenarioSource {
  std::string path;
  std::string document;
  std::vector<std::string> overrides;
  // The name errors give: the path, or "<dict>".
  std::string file() const { return path.empty() ? "<dict>" : path; }
};

// The scenario, loaded and checked as `uavsim validate` loads it.
sim::Scenario LoadSource(const ScenarioSource& source);

// Runs `work` on a thread of its own while the calling thread waits with the
// GIL released, looking every 50 ms for a signal Python recorded (Ctrl-C):
// then the work is asked to stop (core::RequestInterrupt), waited for, and
// Python's exception (KeyboardInterrupt) raised. The work's own exception
// is rethrown here.
void RunInterruptibly(const std::function<void()>& work);

// Python methods: name -> (function, window_time) or None (never called), as
// factories for the run. The functions are borrowed: the dict keeps them alive.
sim::HostedMethods HostedFrom(const py::dict& methods);

// While one lives (and `on`), a fork from any thread leaves the child an
// interpreter it can call (the Python methods of a sweep's points, which
// run in forked processes): the forking thread takes the GIL over the fork,
// the child re-initialises Python's state after it (PyOS_AfterFork_Child)
// and releases the GIL. Off, forks are left alone (the children call no
// Python).
class ForkSafety {
 public:
  explicit ForkSafety(bool on);
  ~ForkSafety();
  ForkSafety(const ForkSafety&) = delete;
  ForkSafety& operator=(const ForkSafety&) = delete;

 private:
  bool on_;
};

void BindScenario(py::module_& m);
void BindRun(py::module_& m);
void BindEnvironment(py::module_& m);

}  // namespace uavsim::python
