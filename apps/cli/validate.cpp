#include "apps/cli/validate.h"

#include <cstdio>
#include <iostream>

#include "core/error.h"
#include "sim/run_cost.h"
#include "sim/scenario.h"

namespace uavsim::cli {

using core::UsageError;

int ValidateScenarios(const ParsedArgs& a, const ModelCheck& check_models) {
  if (a.positional.empty())
    throw UsageError("uavsim validate: expected a scenario file (see uavsim validate --help)");
  if (a.Has("--resolved") && a.positional.size() != 1)
    throw UsageError("uavsim validate: --resolved prints one scenario: give one file");
  const std::vector<std::string> record = RecordList("validate", a);
  // Each file on its own: a bad one gets its line on stderr and the rest are
  // still checked; the exit code is 2 if any was bad.
  int exit_code = kExitOk;
  for (const std::string& file : a.positional) {
    try {
      const sim::Scenario s = sim::LoadScenario(file, Overrides(a));
      check_models(s, file, a.Has("--quiet"));
      if (a.Has("--resolved")) std::cout << sim::ResolvedJson(s).dump(2) << "\n";
      if (!a.Has("--quiet") && !a.Has("--resolved")) {
        const auto e = sim::EstimateResources(s);
        std::printf(
            "%s: ok (%zu UAV%s, %zu node%s, %g s simulated, %.3g rays per simulated second; "
            "about %s of wall time here",
            file.c_str(), s.uavs.size(), s.uavs.size() == 1 ? "" : "s", s.nodes.size(),
            s.nodes.size() == 1 ? "" : "s", s.duration_s, e.rays_per_s,
            Duration(sim::EstimateWallSeconds(s)).c_str());
        if (!record.empty())
          std::printf("; --record writes at most %.3g bytes", sim::EstimateRecordBytes(s, record));
        std::printf(")\n");
        std::fflush(stdout);
      }
    } catch (const core::ConfigError& e) {
      if (a.positional.size() == 1) throw;
      std::cerr << e.what() << std::endl;
      exit_code = kExitBadInput;
    }
  }
  return exit_code;
}

}  // namespace uavsim::cli
