// `uavsim reproduce`: the paper's Sec. VI on simulated data, with verdicts.
#include <cstdio>
#include <iostream>

#include "apps/cli/cli.h"
#include "apps/reproduce/reproduce.h"
#include "core/error.h"
#include "sim/scenario.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

const char* kHelp =
    "usage: uavsim reproduce [--scenario S] [--quick] [--jobs N] [--out DIR] [--seeds K]\n"
    "                        [--episodes N] [--set /ptr=value]... [--wait] [--quiet]\n"
    "       mpirun -np K uavsim reproduce ... (ranks share the episodes and the trainings)\n"
    "\n"
    "Re-runs the evaluation of the paper's Sec. VI on simulated data: simulates four\n"
    "episode sets of the same flights (nodes pre-processing all, none, LiDAR and radar\n"
    "only, the camera only), trains every variant the figures need (uavsim train\n"
    "--variant) at every latent size and training seed, scores them on held-out\n"
    "trajectories, and writes one CSV and one PNG per artefact (Figs. 7-15, Tables II-IV),\n"
    "claims.csv, report.md and report.html: each result beside the paper's claim with a\n"
    "verdict (holds / does not hold / not resolved / mixed) from intervals over seeds, and\n"
    "for each comparison not resolved the seeds it would need (--seeds K trains that many;\n"
    "the seeds already trained in DIR are kept). uavsim report DIR redraws the verdicts\n"
    "from claims.csv alone.\n"
    "Cached and resumable: DIR/episodes/*.eps and DIR/models/<training>/ are kept; a killed\n"
    "reproduction loses only the trainings under way and the same command resumes.\n"
    "\n"
    "  --scenario S   city (default: scenarios/default.json), twin (scenarios/mmaud_twin.json)\n"
    "                 or a scenario file\n"
    "  --quick        every artefact at toy size (6 episodes of 5 s, 2 epochs, 2 seeds, z 4,\n"
    "                 16, 64): minutes, for a first look and CI; its numbers say nothing\n"
    "                 about the paper\n"
    "  --jobs N       trainings (and episodes) at a time, each in its own process with one\n"
    "                 LibTorch thread (default 1; per rank under mpirun)\n"
    "  --out DIR      default runs/reproduce-NAME (-quick with --quick)\n"
    "  --seeds K      training seeds (default 3; quick 2); on an existing DIR only the\n"
    "                 seeds it lacks are trained\n"
    "  --episodes N   flights per episode set (default 30; quick 6)\n"
    "  --set P=V      override the scenario's value at JSON pointer P\n"
    "  --wait         when another reproduction runs in DIR (its lock DIR/.lock), wait for\n"
    "                 it instead of refusing (exit 2, naming its process)\n"
    "\n"
    "exit codes: 0 reported, 1 some trainings failed (rerun to retry them), 2 bad input,\n"
    "130 interrupted (finished trainings are kept)\n";

int Reproduce(const ParsedArgs& a, int argc, char** argv) {
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

std::string Help() { return kHelp; }

}  // namespace

Command ReproduceCommand() {
  return {"reproduce",
          "reproduce [--scenario S]",
          "the paper's Sec. VI: every figure and table, with verdicts",
          {{"--scenario", true},
           {"--out", true},
           {"--jobs", true},
           {"--seeds", true},
           {"--episodes", true},
           {"--set", true},
           {"--quick", false},
           {"--wait", false}},
          Help,
          Reproduce};
}

}  // namespace uavsim::cli
