// uavsim.run and the commands from Python: a run into its directory (the
// same files as `uavsim run` writes, byte for byte, wall times aside), and
// any command of the command line run in-process (`uavsim.sweep`, `train`,
// `dataset`, `report`, `reproduce`), each on a thread of its own so that
// Ctrl-C stops it (RunInterruptibly).
#include <pybind11/stl.h>

#include <memory>

#include "apps/cli/cli.h"
#include "apps/python/bindings.h"
#include "sim/edge_server.h"
#include "sim/run.h"
#include "sim/run_cost.h"

namespace uavsim::python {
namespace {

py::dict SummaryDict(const sim::RunSummary& s) {
  py::dict d;
  d["sim_s"] = s.sim_s;
  d["wall_s"] = s.wall_s;
  py::dict rmse, common;
  for (const auto& [method, value] : s.rmse_m)
    rmse[py::str(method)] = value ? py::object(py::float_(*value)) : py::object(py::none());
  for (const auto& [method, value] : s.rmse_common_m) common[py::str(method)] = value;
  d["rmse_m"] = rmse;
  d["rmse_common_m"] = common;
  d["common_windows"] = s.common_windows;
  return d;
}

struct RunArgs {
  ScenarioSource source;
  sim::RunOptions options;
};

// What `uavsim run` does between parsing and printing (apps/cli/run.cpp).
sim::RunSummary RunSource(RunArgs& a, const sim::HostedMethods& hosted) {
  const sim::Scenario s = LoadSource(a.source);
  a.options.scenario_file = a.source.file();
  a.options.hosted = &hosted;
  sim::CheckTrainedModel(s, a.source.file(), a.options.quiet, &hosted);
  sim::RequireRoomToRecord(s, a.options.record, a.options.out_dir, "uavsim.run");
  return sim::RunScenario(s, a.options);
}

// Runs argv (argv[0] "uavsim") as the command line would; returns its exit
// code. `methods`: Python methods the command's runs may list (a sweep's
// points run them in the processes it forks: ForkSafety).
int Command(std::vector<std::string> args, const py::dict& methods) {
  int rc = 0;
  const sim::HostedMethods hosted = HostedFrom(methods);
  const sim::ScopedProcessHostedMethods scoped(hosted.empty() ? nullptr : &hosted);
  const ForkSafety fork_safety(!hosted.empty());
  RunInterruptibly([&] {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    rc = cli::RunCommandLine(static_cast<int>(args.size()), argv.data());
  });
  return rc;
}

}  // namespace

void BindRun(py::module_& m) {
  m.def(
      "run",
      [](const std::string& path, const std::string& document,
         const std::vector<std::string>& overrides, const std::string& out_dir, bool force,
         bool quiet, bool report, const std::vector<std::string>& record,
         const std::string& trace_dir, const std::string& replay_dir, const py::dict& methods) {
        RunArgs a{{path, document, overrides}, {}};
        a.options.out_dir = out_dir;
        a.options.force = force;
        a.options.quiet = quiet;
        a.options.report = report;
        a.options.record = record;
        a.options.trace_dir = trace_dir;
        a.options.replay_dir = replay_dir;
        const sim::HostedMethods hosted = HostedFrom(methods);
        sim::RunSummary summary;
        RunInterruptibly([&] { summary = RunSource(a, hosted); });
        return SummaryDict(summary);
      },
      py::arg("path"), py::arg("document"), py::arg("overrides"), py::arg("out_dir"),
      py::arg("force"), py::arg("quiet"), py::arg("report"), py::arg("record"),
      py::arg("trace_dir"), py::arg("replay_dir"), py::arg("methods"),
      "One run into out_dir (the package's uavsim.run is the interface).");
  m.def("command", &Command, py::arg("argv"), py::arg("methods") = py::dict(),
        "Runs a uavsim command line in this process; returns its exit code.");
}

}  // namespace uavsim::python
