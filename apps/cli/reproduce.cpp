// `uavsim reproduce`: the paper's Sec. VI on simulated data, with verdicts.
#include <cstdio>
#include <iostream>

#include "apps/cli/cli.h"
#include "apps/reproduce/reproduce.h"
#include "core/error.h"
#include "sim/scenario.h"

namespace uavsim::cli {
using core::UsageError;

int RunReproduceCommand(const ParsedArgs& a, int argc, char** argv) {
  if (!a.positional.empty())
    throw UsageError("uavsim reproduce: unexpected argument '" + a.positional[0] +
                     "' (the scenario goes after --scenario; see uavsim reproduce --help)");
  sim::ReproduceOptions o;
  o.wait = a.Has("--wait");
  o.quick = a.Has("--quick");
  o.quiet = a.Has("--quiet");
  const std::string scenario = a.Value("--scenario").value_or("city");
  o.scenario_file = scenario == "city"   ? "scenarios/default.json"
                    : scenario == "twin" ? "scenarios/mmaud_twin.json"
                                         : scenario;
  if (auto v = a.Value("--jobs"))
    o.jobs = static_cast<int>(UnsignedOption("reproduce", "--jobs", *v, 1024));
  if (auto v = a.Value("--seeds"))
    o.seeds = static_cast<int>(UnsignedOption("reproduce", "--seeds", *v, 100));
  if (auto v = a.Value("--episodes"))
    o.episodes = static_cast<int>(UnsignedOption("reproduce", "--episodes", *v, 100000));
  if (o.jobs < 1 || (a.Value("--seeds") && o.seeds < 1) ||
      (a.Value("--episodes") && o.episodes < 3))
    throw UsageError("uavsim reproduce: --jobs and --seeds need at least 1, --episodes at least 3");
  o.command_line = CommandLine(argc, argv);
  const sim::Scenario s = sim::LoadScenario(o.scenario_file, Overrides(a));
  o.out_dir = a.Value("--out").value_or("runs/reproduce-" + s.name + (o.quick ? "-quick" : ""));
  const sim::ReproduceOutcome r = sim::RunReproduce(s, o);
  if (r.mpi_worker) return r.failed ? kExitFailure : kExitOk;
  for (const std::string& w : r.warnings) std::cerr << "uavsim: warning: " << w << "\n";
  if (r.failed) {
    std::cerr << "uavsim reproduce: " << r.failed << " of " << r.arms
              << " trainings failed or did not run (messages above); rerun the same command "
                 "to retry them\n";
    return kExitFailure;
  }
  if (!o.quiet)
    std::printf("%zu trainings (%zu already done, %zu now) in %.0f s; report: %s/report.html\n",
                r.arms, r.already_done, r.ran, r.wall_s, o.out_dir.c_str());
  return kExitOk;
}

}  // namespace uavsim::cli
