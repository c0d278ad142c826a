// `uavsim bench events`: throughput of the discrete-event core in the hold
// model of ns-3's utils/bench-scheduler.cc.
#pragma once

#include <ostream>

namespace uavsim::sim {

// Hold model: N events are scheduled at exponential delays (mean 100 ns, as in
// ns-3's bench-scheduler, and 1 ms), then each executed event schedules one
// new event at Now() + a fresh exponential delay, so N stay pending. The event
// is a small lambda capturing one pointer. Runs N = 1e3, 1e4, 1e5, 1e6 on
// core::Simulator, and N = 1e5 on a plain std::priority_queue of
// std::function for comparison, and writes one table row per run to `out`:
// queue, mean delay, pending, events timed, seconds (wall), million events per
// second. With `quiet` only the table is written (no description line).
//
// Google Benchmark times the event loop (wall clock) in batches of 1e5
// events for at least 0.4 s per row; prefilling and an untimed warm-up of
// max(N, 1e6) events come first. The delays come from a fixed-seed
// RngStream, so every run executes the same sequence of events; only the
// timings and how many events the timing takes vary. Takes several seconds.
// Returns 0.
int BenchEvents(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
