// `uavsim sweep` as typed: its usage, options and help (its body:
// apps/cli/sweep.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

const char* kHelp =
    "usage: uavsim sweep SPEC.json [--out DIR] [--jobs N] [--shard I/N] [--wait]\n"
    "                              [--no-traces | --keep-traces] [--quiet]\n"
    "       uavsim sweep merge DIR [--quiet]\n"
    "       mpirun -np K uavsim sweep SPEC.json [--out DIR] [--jobs N]\n"
    "\n"
    "Runs the Cartesian grid of scenario variations in SPEC.json (parameters as JSON\n"
    "pointers into a base scenario with lists, ranges or named cases of values, times\n"
    "the seeds), each point a run directory DIR/points/<id>/ (default DIR: runs/NAME).\n"
    "Every point is checked before anything runs. Rerunning the same command resumes:\n"
    "finished points are kept, killed ones redone. When all points are done, DIR gets\n"
    "summary.csv (a row per point), aggregate.csv (mean and 95 % confidence interval over\n"
    "the seeds), plots/ (RMSE, coverage and delivery vs each numeric parameter as small\n"
    "multiples with confidence bands, rate vs SNR per setting) and report.html, which\n"
    "shows them (`uavsim report DIR` redraws it). The spec format is in\n"
    "scenarios/sweeps/README.md.\n"
    "\n"
    "  --out DIR     the sweep folder (default runs/NAME)\n"
    "  --jobs N      points at a time (default 1; each gets cores / N threads); under\n"
    "                mpirun, per rank: rank 0 hands points to ranks as they free up\n"
    "  --shard I/N   run only the points whose index is I modulo N (0 <= I < N), e.g. a\n"
    "                Slurm array task; then `uavsim sweep merge DIR` writes the tables\n"
    "  --wait        when another sweep runs in DIR (its lock DIR/.lock), wait for it\n"
    "                instead of refusing (exit 2, naming its process)\n"
    "  --no-traces   every point senses its world itself; by default points that differ\n"
    "                only in links, methods or beams sense once: the first writes\n"
    "                DIR/traces/KEY.trace, the others replay it (the same outputs, byte for\n"
    "                byte; docs/speed.md)\n"
    "  --keep-traces keep DIR/traces when the sweep is complete (removed by default)\n"
    "  --quiet       no progress or summary output\n"
    "exit codes: 0 all points done, 1 some points failed (rerun to retry them), 2 bad\n"
    "input, 130 interrupted (finished points are kept)\n";

std::string Help() { return kHelp; }

}  // namespace

Command SweepCommand() {
  return {"sweep",
          "sweep SPEC.json",
          "run a grid of scenarios (packet loss x weather x seeds)",
          {{"--out", true},
           {"--jobs", true},
           {"--shard", true},
           {"--wait", false},
           {"--no-traces", false},
           {"--keep-traces", false}},
          Help,
          RunSweepCommand};
}

}  // namespace uavsim::cli
