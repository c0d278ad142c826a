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

}  // namespace

int RunSweepCommand(const ParsedArgs& a, int, char**) {
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

}  // namespace uavsim::cli
