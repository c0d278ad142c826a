// `uavsim reproduce` as typed: its usage, options and help (its body:
// apps/cli/reproduce.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

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
          RunReproduceCommand};
}

}  // namespace uavsim::cli
