#include "apps/bench/bench_events.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <iomanip>
#include <queue>
#include <utility>
#include <vector>

#include "apps/bench/gbench.h"
#include "core/rng.h"
#include "core/simulator.h"
#include "core/time.h"

namespace uavsim::sim {
namespace {

using core::SimTime;

constexpr std::uint64_t kSeed = 1;
// Google Benchmark's iteration: a batch of events, about 3-20 ms.
constexpr std::uint64_t kEventsPerIteration = 100'000;
constexpr std::uint64_t kWarmupEvents = 1'000'000;
constexpr double kMinTimeS = 0.4;

// The naive alternative: a binary heap of std::function, as a DES written in
// an afternoon would have it. Same interface as core::Simulator for Hold.
class PlainQueue {
 public:
  template <typename F>
  void ScheduleAt(SimTime t_ns, F&& fn) {
    queue_.push(Entry{t_ns, sequence_++, std::function<void()>(std::forward<F>(fn))});
  }
  template <typename F>
  void ScheduleAfter(SimTime delay_ns, F&& fn) {
    ScheduleAt(now_ + delay_ns, std::forward<F>(fn));
  }
  void Stop() { stop_ = true; }
  void Run() {
    stop_ = false;
    while (!queue_.empty() && !stop_) {
      // Moving out of top() is safe: the comparison reads only time and
      // sequence, and the entry is popped right away.
      Entry entry = std::move(const_cast<Entry&>(queue_.top()));
      queue_.pop();
      now_ = entry.time;
      entry.fn();
    }
  }

 private:
  struct Entry {
    SimTime time;
    std::uint64_t sequence;
    std::function<void()> fn;
  };
  struct Later {
    bool operator()(const Entry& a, const Entry& b) const {
      return a.time > b.time || (a.time == b.time && a.sequence > b.sequence);
    }
  };
  std::priority_queue<Entry, std::vector<Entry>, Later> queue_;
  SimTime now_ = 0;
  std::uint64_t sequence_ = 0;
  bool stop_ = false;
};

template <typename Sim>
struct Hold {
  Sim* sim;
  core::RngStream rng;
  std::uint64_t executed;
  std::uint64_t total;
  double mean_delay_ns;

  SimTime Delay() { return static_cast<SimTime>(std::llround(rng.Exponential(mean_delay_ns))); }

  // Keeps the population constant: every event schedules its successor.
  static void Event(Hold* hold) {
    if (++hold->executed == hold->total) hold->sim->Stop();
    hold->sim->ScheduleAfter(hold->Delay(), [hold] { Event(hold); });
  }
};

struct Row {
  const char* queue;
  double mean_delay_ns;
  std::size_t pending;
  std::uint64_t events;
  double seconds;
  double events_per_s;
};

// Prefills `pending` events and runs an untimed warm-up (ns-3 primes too):
// the queue's buffers reach their steady size, so the timed part measures
// events, not page faults. Then Google Benchmark times batches of
// kEventsPerIteration events of the same hold model.
template <typename Sim>
Row RunHold(const char* name, double mean_delay_ns, std::size_t pending) {
  Sim sim;
  const std::uint64_t warmup = std::max<std::uint64_t>(pending, kWarmupEvents);
  Hold<Sim> hold{&sim, core::RngStream(kSeed, "bench/events"), 0, warmup, mean_delay_ns};
  for (std::size_t i = 0; i < pending; ++i) {
    sim.ScheduleAt(hold.Delay(), [h = &hold] { Hold<Sim>::Event(h); });
  }
  sim.Run();
  gbench::Register(name,
                   [&](benchmark::State& state) {
                     for (auto _ : state) {
                       hold.total += kEventsPerIteration;
                       sim.Run();
                     }
                     state.counters["events"] =
                         benchmark::Counter(static_cast<double>(kEventsPerIteration),
                                            benchmark::Counter::kIsIterationInvariantRate);
                   })
      ->Unit(benchmark::kMillisecond)
      ->MinTime(kMinTimeS);
  const gbench::Measurement m = gbench::RunSingle().Fastest();
  return Row{name,        mean_delay_ns,
             pending,     static_cast<std::uint64_t>(m.iterations) * kEventsPerIteration,
             m.seconds(), m.Counter("events")};
}

void PrintRow(std::ostream& out, const Row& row) {
  out << std::left << std::setw(34) << row.queue << std::right << std::setw(11)
      << (row.mean_delay_ns >= 1e6
              ? std::to_string(static_cast<int>(row.mean_delay_ns / 1e6)) + " ms"
              : std::to_string(static_cast<int>(row.mean_delay_ns)) + " ns")
      << std::setw(9) << row.pending << std::setw(11) << row.events << std::fixed
      << std::setprecision(3) << std::setw(9) << row.seconds << std::setprecision(2)
      << std::setw(12) << row.events_per_s * 1e-6 << std::defaultfloat << '\n'
      << std::flush;
}

}  // namespace

int BenchEvents(bool quiet, std::ostream& out) {
  if (!quiet) {
    out << "hold model (ns-3 bench-scheduler): each event schedules one more at an exponential "
           "delay (mean 100 ns as ns-3's default, and 1 ms: few ties); seed "
        << kSeed << "\n";
  }
  out << std::left << std::setw(34) << "queue" << std::right << std::setw(11) << "mean delay"
      << std::setw(9) << "pending" << std::setw(11) << "events" << std::setw(9) << "seconds"
      << std::setw(12) << "M events/s" << '\n';
  for (double mean_delay_ns : {100.0, 1e6}) {
    for (std::size_t pending : {1'000, 10'000, 100'000, 1'000'000}) {
      PrintRow(out, RunHold<core::Simulator>("core::Simulator", mean_delay_ns, pending));
    }
    PrintRow(out,
             RunHold<PlainQueue>("std::priority_queue<std::function>", mean_delay_ns, 100'000));
  }
  return 0;
}

}  // namespace uavsim::sim
