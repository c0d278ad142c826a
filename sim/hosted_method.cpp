#include "sim/hosted_method.h"

#include "core/error.h"
#include "sim/scenario.h"

namespace uavsim::sim {
namespace {
const HostedMethods* process_methods = nullptr;
}  // namespace

const HostedMethods* ProcessHostedMethods() { return process_methods; }

ScopedProcessHostedMethods::ScopedProcessHostedMethods(const HostedMethods* methods)
    : previous_(process_methods) {
  process_methods = methods;
}

ScopedProcessHostedMethods::~ScopedProcessHostedMethods() { process_methods = previous_; }

const HostedMethods* HostedOrProcess(const HostedMethods* provided) {
  return provided ? provided : process_methods;
}

void CheckHostedMethods(const Scenario& s, const std::string& file, const HostedMethods* provided) {
  provided = HostedOrProcess(provided);
  const auto& methods = s.pipeline.methods;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    if (!s.pipeline.FindHosted(methods[i])) continue;
    if (provided && provided->count(methods[i])) continue;
    throw core::ConfigError(
        file, "/pipeline/methods/" + std::to_string(i),
        "\"" + methods[i] +
            "\" is a Python method: it runs only from Python, with its function given "
            "(uavsim.run(..., methods=[uavsim.PythonMethod(\"" +
            methods[i] + "\", fn)]))");
  }
}

}  // namespace uavsim::sim
