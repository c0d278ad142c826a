#include "apps/bench/bench_link.h"

#include <cstdint>
#include <iomanip>
#include <string>
#include <vector>

#include "apps/bench/gbench.h"
#include "channel/link_config.h"
#include "channel/packet.h"
#include "channel/uplink.h"
#include "core/rng.h"
#include "core/simulator.h"
#include "core/time.h"
#include "core/weather.h"

namespace uavsim::sim {
namespace {

using core::SimTime;

constexpr std::uint64_t kSeed = 1;
// Google Benchmark's iteration: this many message periods of simulated time.
constexpr std::uint64_t kMessagesPerIteration = 10'000;
constexpr double kMinTimeS = 0.1;

struct Case {
  const char* name;
  channel::LinkConfig link;
  core::WeatherConfig weather;
  std::uint32_t message_bytes;
  SimTime period_ns;
  std::uint64_t warmup_messages;
};

// Sends one message per period; each send schedules the next, as a sensor's
// frame clock does.
struct Source {
  core::Simulator* sim;
  channel::Uplink* link;
  std::uint32_t bytes;
  SimTime period_ns;
  std::uint64_t sent;
  std::uint64_t total;

  static void Tick(Source* s) {
    channel::Message m;
    m.modality = channel::Modality::kCamera;
    m.sequence = s->sent;
    m.t_capture_ns = s->sim->Now();
    m.payload_bytes = s->bytes;
    s->link->Send(std::move(m));
    if (++s->sent < s->total) s->sim->ScheduleAfter(s->period_ns, [s] { Tick(s); });
  }
};

struct Row {
  std::uint64_t messages = 0;
  std::uint64_t fragments = 0;
  std::uint64_t lost = 0;
  double seconds = 0.0;
  double messages_per_s = 0.0;
  double fragments_per_s = 0.0;
};

// The source never stops; Google Benchmark decides how many periods it times.
// The link's counts are taken around the timed loop of the reported run.
Row Run(const Case& c) {
  core::Simulator sim;
  channel::Uplink link(sim, c.link, c.weather, core::RngStream(kSeed, "bench/link"));
  std::uint64_t arrivals = 0;
  link.SetArrivalCallback([&arrivals](const channel::Message&, SimTime) { ++arrivals; });
  Source source{&sim, &link, c.message_bytes, c.period_ns, 0, UINT64_MAX};
  sim.ScheduleAt(0, [s = &source] { Source::Tick(s); });

  // Untimed warm-up: the in-flight pool, the buffer and the event slab reach
  // their working size.
  SimTime until_ns = static_cast<SimTime>(c.warmup_messages) * c.period_ns - 1;
  sim.RunUntil(until_ns);
  channel::UplinkStats before, after;
  gbench::Register(
      c.name,
      [&](benchmark::State& state) {
        before = link.stats();
        for (auto _ : state) {
          until_ns += static_cast<SimTime>(kMessagesPerIteration) * c.period_ns;
          sim.RunUntil(until_ns);
        }
        after = link.stats();
        using benchmark::Counter;
        state.counters["messages"] = Counter(
            static_cast<double>(after.messages_sent - before.messages_sent), Counter::kIsRate);
        state.counters["fragments"] = Counter(
            static_cast<double>(after.fragments_sent - before.fragments_sent), Counter::kIsRate);
      })
      ->Unit(benchmark::kMillisecond)
      ->MinTime(kMinTimeS);
  const gbench::Measurement m = gbench::RunSingle().Fastest();
  Row row;
  row.messages = after.messages_sent - before.messages_sent;
  row.fragments = after.fragments_sent - before.fragments_sent;
  row.lost = after.messages_lost - before.messages_lost;
  row.seconds = m.seconds();
  row.messages_per_s = m.Counter("messages");
  row.fragments_per_s = m.Counter("fragments");
  return row;
}

std::vector<Case> Cases() {
  std::vector<Case> cases;
  {
    channel::LinkConfig l;
    l.bandwidth_mbps = 100.0;
    l.loss.p = 0.01;
    l.jitter.type = channel::JitterType::kNormal;
    l.jitter.std_ms = 1.0;
    // 108 B on the wire: 8.64 us at 100 Mbps.
    cases.push_back({"latent 80 B, bernoulli, jitter",
                     l,
                     {},
                     channel::LatentMessageBytes(16),
                     10'000,
                     200'000});
  }
  {
    channel::LinkConfig l;
    l.bandwidth_mbps = 1000.0;
    l.loss.type = channel::LossType::kGilbertElliott;
    l.loss.p = 0.001;
    l.loss.r = 0.3;
    l.jitter.type = channel::JitterType::kUniform;
    l.jitter.max_ms = 0.5;
    l.carrier_ghz = 28.0;
    l.snr_db = 30.0;
    core::WeatherConfig rain;
    rain.rain_mm_h = 10.0;
    // 65536 B: 44 full fragments and one of 752 B, 66780 B on the wire: 534 us.
    cases.push_back({"frame 64 KiB, gilbert-elliott, rain", l, rain, 65536, 615'000, 20'000});
  }
  {
    channel::LinkConfig l;
    l.buffer_packets = 100;
    // 1500 B on the wire take 600 us at 20 Mbps; one arrives every 300 us.
    cases.push_back({"overload 2x, drop-tail 100", l, {}, 1472, 300'000, 200'000});
  }
  return cases;
}

}  // namespace

int BenchLink(bool quiet, std::ostream& out) {
  if (!quiet) {
    out << "one source through one channel::Uplink on core::Simulator; seed " << kSeed
        << "; timed by Google Benchmark after an untimed warm-up\n";
  }
  out << std::left << std::setw(38) << "case" << std::right << std::setw(10) << "messages"
      << std::setw(11) << "fragments" << std::setw(8) << "lost %" << std::setw(9) << "seconds"
      << std::setw(12) << "k msg/s" << std::setw(12) << "M frag/s" << '\n';
  for (const Case& c : Cases()) {
    const Row r = Run(c);
    out << std::left << std::setw(38) << c.name << std::right << std::setw(10) << r.messages
        << std::setw(11) << r.fragments << std::fixed << std::setprecision(1) << std::setw(8)
        << 100.0 * static_cast<double>(r.lost) / static_cast<double>(r.messages)
        << std::setprecision(3) << std::setw(9) << r.seconds << std::setprecision(0)
        << std::setw(12) << r.messages_per_s * 1e-3 << std::setprecision(2) << std::setw(12)
        << r.fragments_per_s * 1e-6 << std::defaultfloat << '\n'
        << std::flush;
  }
  return 0;
}

}  // namespace uavsim::sim
