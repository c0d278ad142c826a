// Scenarios from Python: loaded, checked and resolved as the command line
// does it (`uavsim validate`, `--set`, `--resolved`).
#include <pybind11/stl.h>

#include "apps/python/bindings.h"
#include "core/json_io.h"
#include "sim/edge_server.h"
#include "sim/scenario.h"

namespace uavsim::python {

sim::Scenario LoadSource(const ScenarioSource& source) {
  if (!source.path.empty()) return sim::LoadScenario(source.path, source.overrides);
  core::Json doc = core::ParseJsonText(source.document, source.file());
  for (const std::string& o : source.overrides) sim::ApplyOverride(doc, o, source.file());
  return sim::ScenarioFromJson(doc, source.file(), ".");
}

namespace {

ScenarioSource Source(const std::string& path, const std::string& document,
                      const std::vector<std::string>& overrides) {
  return {path, document, overrides};
}

// Every rule `uavsim validate` checks, the trained model's too; `hosted`:
// the names of the Python methods that will be given.
void Validate(const ScenarioSource& source, const std::vector<std::string>& hosted) {
  const sim::Scenario s = LoadSource(source);
  py::dict names;  // functions that are never called: a check loads, it does not run
  for (const std::string& name : hosted) names[py::str(name)] = py::none();
  const sim::HostedMethods provided = HostedFrom(names);
  sim::CheckTrainedModel(s, source.file(), /*quiet=*/true, &provided);
}

}  // namespace

void BindScenario(py::module_& m) {
  m.def(
      "resolved",
      [](const std::string& path, const std::string& document,
         const std::vector<std::string>& overrides) {
        return sim::ResolvedJson(LoadSource(Source(path, document, overrides))).dump();
      },
      "The scenario with every default filled, as JSON text.");
  m.def(
      "validate",
      [](const std::string& path, const std::string& document,
         const std::vector<std::string>& overrides, const std::vector<std::string>& hosted) {
        Validate(Source(path, document, overrides), hosted);
      },
      "Checks the scenario as `uavsim validate` does; raises ScenarioError.");
}

}  // namespace uavsim::python
