// Methods a host program supplies (pipeline::HostedMethod: /pipeline/methods
// entries {"type": "python", ...}): `import uavsim` (apps/python) hands the
// run one factory per name; the engine knows nothing of Python. A scenario
// that lists one and is run without it (the command line) is refused.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "pipeline/localization_method.h"
#include "pipeline/pipeline_config.h"

namespace uavsim::sim {

struct Scenario;

// Makes the method of a hosted entry for latents of `latent_dim` values and
// windows of `window_s` seconds.
using HostedMethodFactory = std::function<std::unique_ptr<pipeline::LocalizationMethod>(
    const pipeline::HostedMethod& entry, int latent_dim, double window_s)>;
using HostedMethods = std::map<std::string, HostedMethodFactory>;

// The factories a run uses when it is given none (null: none), for the
// process: the Python module sets them while a command it runs in-process
// (a sweep) makes runs of its own. Not thread-safe: set between runs.
const HostedMethods* ProcessHostedMethods();
class ScopedProcessHostedMethods {
 public:
  explicit ScopedProcessHostedMethods(const HostedMethods* methods);
  ~ScopedProcessHostedMethods();
  ScopedProcessHostedMethods(const ScopedProcessHostedMethods&) = delete;
  ScopedProcessHostedMethods& operator=(const ScopedProcessHostedMethods&) = delete;

 private:
  const HostedMethods* previous_;
};

// `provided`, or the process's when it is null.
const HostedMethods* HostedOrProcess(const HostedMethods* provided);

// Every hosted entry of /pipeline/methods has a factory in `provided` (null:
// the process's): else core::ConfigError naming `file` and the entry's
// /pipeline/methods/i.
void CheckHostedMethods(const Scenario& s, const std::string& file, const HostedMethods* provided);

}  // namespace uavsim::sim
