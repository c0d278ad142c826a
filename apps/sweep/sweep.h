// Running a sweep (apps/sweep/sweep_spec.h): every grid point is a whole run
// directory DIR/points/<id>/, run in a child process of its own (so a
// crash or a kill costs one point, and each point gets its own cores).
//
//  - local: --jobs N points at a time; a terminal shows points done, rate
//    and ETA.
//  - resumable: a point counts as done when DIR/points/<id>/ exists (run
//    directories appear all at once); a rerun skips those and redoes the
//    rest; staging folders left by killed points are removed.
//  - under mpirun: rank 0 hands out points one at a time to whichever rank
//    asks (slow points do not stall the rest) and runs points itself; other
//    ranks run theirs in a private temporary folder and send the files back,
//    so only rank 0 writes DIR (no shared file system needed).
//  - sensing once: points whose sensing keys match (sim/sensing_trace.h)
//    sense once; the others replay that trace (DIR/traces/). A point whose
//    trace is not on its host's file system (a rank without DIR) senses.
//  - --shard I/N: only the points whose index is I modulo N (a batch
//    scheduler's array task); `uavsim sweep merge DIR` then writes the
//    tables and plots once every shard is done.
//
// DIR/sweep.json records the expanded grid; a rerun into a DIR made by
// another spec is refused. When every point is done, DIR gets summary.csv,
// aggregate.csv and plots/ (results/sweep_report.h).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "apps/sweep/process_farm.h"  // UnderMpirun
#include "apps/sweep/sweep_spec.h"

namespace uavsim::sim {

struct SweepOptions {
  std::string out_dir;  // DIR
  int jobs = 1;         // points at a time on this process (each rank under MPI)
  int shard_index = 0;  // --shard I/N
  int shard_count = 1;
  bool quiet = false;
  // Another sweep holds DIR's lock (the same shard): wait for it instead of
  // refusing (core::UsageError naming its process).
  bool wait = false;
  // Sensing traces (sim/sensing_trace.h): points that differ only in what
  // cannot change sensing (links, methods, beams) share one sensing pass.
  // The first point of each such group writes DIR/traces/KEY.trace, the
  // others wait for it and replay it (the same outputs, byte for byte).
  // false: every point senses (--no-traces).
  bool traces = true;
  // Keep DIR/traces when the sweep is complete (else removed).
  bool keep_traces = false;
};

struct SweepOutcome {
  std::size_t points = 0;        // in the grid
  std::size_t already_done = 0;  // found finished when the sweep started
  std::size_t ran = 0;           // finished by this invocation
  std::size_t failed = 0;
  std::size_t missing = 0;  // other shards' points not finished yet
  bool reported = false;    // summary.csv and plots written
  bool mpi_worker = false;  // a rank other than 0: it reports nothing
  int ranks = 1;
  std::vector<std::string> warnings;
};

// DIR's file .lock (a shard's: .lock-shard-I-of-N) is flock'ed while the
// sweep runs. Throws core::UsageError for a DIR made by another spec or
// whose lock another sweep holds (unless options.wait), Interrupted when
// a termination signal arrived (finished points stay), std::runtime_error
// for I/O failures.
SweepOutcome RunSweep(const SweepSpec& spec, const SweepOptions& options);

// Writes the tables and plots of DIR from its finished points. Throws
// core::UsageError if DIR is not a sweep or points are missing.
SweepOutcome MergeSweep(const std::string& dir);

}  // namespace uavsim::sim
