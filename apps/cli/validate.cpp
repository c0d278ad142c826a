// `uavsim validate`: checks scenarios strictly and says what a run of each
// would cost here.
#include <cstdio>
#include <iostream>

#include "apps/cli/cli.h"
#include "core/error.h"
#include "sim/edge_server.h"
#include "sim/run_cost.h"
#include "sim/scenario.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

const char* kHelp =
    "usage: uavsim validate SCENARIO.json [MORE.json]... [--set /json/pointer=value]...\n"
    "                       [--record camera,lidar,radar,mcap] [--resolved] [--quiet]\n"
    "\n"
    "Checks each SCENARIO.json strictly (unknown keys, types, ranges, references, files,\n"
    "meshes, the trained model's manifest and checksums, resource limits: rays and\n"
    "memory against this machine's). Exit 0 if all are valid, else exit 2 with one line\n"
    "on stderr per invalid file:\n"
    "  FILE: /json/pointer: expected ..., got ...\n"
    "\n"
    "  --set P=V     override the value at JSON pointer P (V is JSON, or a bare string),\n"
    "                in every file\n"
    "  --resolved    print the scenario with every default filled, as JSON, on stdout\n"
    "                (one file only)\n"
    "  --record LIST also say how many bytes `run --record LIST` would write at most\n"
    "  --quiet       print nothing on success\n";

int Validate(const ParsedArgs& a, int, char**) {
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
      sim::CheckTrainedModel(s, file, a.Has("--quiet"));
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

std::string Help() { return kHelp; }

}  // namespace

Command ValidateCommand() {
  return {"validate",
          "validate SCENARIO.json",
          "check a scenario; exit 0, or exit 2 with FILE: /json/pointer: message",
          {{"--set", true}, {"--record", true}, {"--resolved", false}},
          Help,
          Validate};
}

}  // namespace uavsim::cli
