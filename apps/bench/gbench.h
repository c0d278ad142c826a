// Google Benchmark under `uavsim bench`: the timing that every timed bench
// shares. Google Benchmark times; each bench prints its own table from the
// figures collected here.
#pragma once

#include <benchmark/benchmark.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace uavsim::sim::gbench {

// One repetition (or one aggregate over repetitions) of a benchmark, as
// Google Benchmark reports it. Times are in seconds per iteration whatever
// the benchmark's Unit(); `seconds()` is the wall time of all iterations.
struct Measurement {
  std::int64_t iterations = 0;
  double real_s_per_iteration = 0.0;  // wall clock
  double cpu_s_per_iteration = 0.0;   // CPU time of the benchmark's thread
  // User counters as Google Benchmark finishes them: a kIsRate counter is
  // per second of wall time (Register sets UseRealTime), a plain one as set.
  std::map<std::string, double> counters;

  double seconds() const { return real_s_per_iteration * static_cast<double>(iterations); }
  // The counter `name`; throws std::out_of_range naming it if it was not set.
  double Counter(const std::string& name) const;
};

// Every repetition of one benchmark, in order, and with Repetitions(n > 1)
// Google Benchmark's aggregates by name ("mean", "median", "stddev", "cv",
// and any added with ComputeStatistics).
struct Result {
  std::string name;
  std::vector<Measurement> repetitions;
  std::map<std::string, Measurement> aggregates;

  // The repetition with the least wall time per iteration.
  const Measurement& Fastest() const;
  // The aggregate `name`; throws std::out_of_range naming it if absent.
  const Measurement& Aggregate(const std::string& name) const;
};

// Registers `body` under `name` (unique among those registered since the last
// run; std::logic_error otherwise) with wall-clock timing (UseRealTime):
// iteration counts, rates and the reported time all follow the wall clock.
// Returns Google Benchmark's handle for Unit, MinTime, Repetitions, etc. The
// body and what it refers to must live until the next RunRegistered.
benchmark::internal::Benchmark* Register(const std::string& name,
                                         std::function<void(benchmark::State&)> body);

// Runs every benchmark registered since the last call, in registration
// order, with Google Benchmark's runner, then clears the registry (also when
// it throws). Google Benchmark is initialised on the first call with no
// flags of its own (uavsim's command line is not parsed; its BENCHMARK_*
// environment variables still are, and every bench sets its own time or
// iteration count). Writes nothing. Returns one Result per benchmark in
// registration order. Throws std::runtime_error naming the benchmark if one
// reported an error (State::SkipWithError) or produced no result.
std::vector<Result> RunRegistered();

// RunRegistered when exactly one benchmark is registered: its Result.
// Throws std::logic_error if there is not exactly one.
Result RunSingle();

}  // namespace uavsim::sim::gbench
