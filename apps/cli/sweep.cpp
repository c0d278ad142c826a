// `uavsim sweep` and `uavsim sweep merge`: grids of runs and their tables.
#include <cstdio>
#include <iostream>

#include "apps/cli/cli.h"
#include "apps/sweep/sweep.h"
#include "apps/sweep/sweep_spec.h"
#include "core/error.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

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

void PrintSweepOutcome(const std::string& dir, const sim::SweepOutcome& r) {
  std::printf("%s: %zu points: %zu run now, %zu already done, %zu failed", dir.c_str(), r.points,
              r.ran, r.already_done, r.failed);
  if (r.missing > 0) std::printf(", %zu left to other shards", r.missing);
  std::printf("\n");
  if (r.reported)
    std::printf("%s/summary.csv, %s/aggregate.csv, %s/plots/ and %s/report.html written\n",
                dir.c_str(), dir.c_str(), dir.c_str(), dir.c_str());
  else if (r.missing > 0 && r.failed == 0)
    std::printf("when every shard is done: uavsim sweep merge %s\n", dir.c_str());
}

int Sweep(const ParsedArgs& a, int, char**) {
  const bool quiet = a.Has("--quiet");
  if (!a.positional.empty() && a.positional[0] == "merge") {
    if (a.positional.size() != 2 || a.Has("--out") || a.Has("--jobs") || a.Has("--shard"))
      throw UsageError("uavsim sweep merge: expected one sweep folder (see uavsim sweep --help)");
    const auto r = sim::MergeSweep(a.positional[1]);
    for (const std::string& w : r.warnings) std::cerr << "uavsim: warning: " << w << "\n";
    if (!quiet) PrintSweepOutcome(a.positional[1], r);
    return kExitOk;
  }
  if (a.positional.size() != 1)
    throw UsageError("uavsim sweep: expected one sweep spec file (see uavsim sweep --help)");
  sim::SweepOptions o;
  o.quiet = quiet;
  o.wait = a.Has("--wait");
  o.traces = !a.Has("--no-traces");
  o.keep_traces = a.Has("--keep-traces");
  if (!o.traces && o.keep_traces)
    throw UsageError("uavsim sweep: --no-traces and --keep-traces: give one");
  if (auto v = a.Value("--jobs"))
    o.jobs = static_cast<int>(UnsignedOption("sweep", "--jobs", *v, 1024));
  if (o.jobs < 1) throw UsageError("uavsim sweep: --jobs needs at least 1");
  if (auto v = a.Value("--shard")) {
    const auto slash = v->find('/');
    const std::string i = slash == std::string::npos ? *v : v->substr(0, slash);
    const std::string n = slash == std::string::npos ? "" : v->substr(slash + 1);
    if (slash == std::string::npos || i.empty() || n.empty() ||
        i.find_first_not_of("0123456789") != std::string::npos ||
        n.find_first_not_of("0123456789") != std::string::npos || i.size() > 6 || n.size() > 6 ||
        std::stoi(n) < 1 || std::stoi(i) >= std::stoi(n))
      throw UsageError("uavsim sweep: --shard expects I/N with 0 <= I < N, got '" + *v + "'");
    o.shard_index = std::stoi(i);
    o.shard_count = std::stoi(n);
  }
  const sim::SweepSpec spec = sim::LoadSweepSpec(a.positional[0], quiet);
  o.out_dir = a.Value("--out").value_or("runs/" + spec.name);
  const auto r = sim::RunSweep(spec, o);
  if (r.mpi_worker) return r.failed ? kExitFailure : kExitOk;
  for (const std::string& w : r.warnings) std::cerr << "uavsim: warning: " << w << "\n";
  if (!quiet) PrintSweepOutcome(o.out_dir, r);
  if (r.failed) {
    std::cerr << "uavsim sweep: " << r.failed << " of " << r.points
              << " points failed (messages above); rerun the same command to retry them\n";
    return kExitFailure;
  }
  return kExitOk;
}

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
          Sweep};
}

}  // namespace uavsim::cli
