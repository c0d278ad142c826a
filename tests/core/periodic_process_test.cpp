#include "core/periodic_process.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/rng.h"
#include "core/simulator.h"
#include "core/time.h"

namespace {

using uavsim::core::PeriodicProcess;
using uavsim::core::RngStream;
using uavsim::core::Seconds;
using uavsim::core::SimTime;
using uavsim::core::Simulator;

struct Tick {
  std::int64_t k;
  SimTime t_ns;
};

// A process that records its ticks.
struct Recorder {
  std::vector<Tick> ticks;
  PeriodicProcess::Callback callback() {
    return [this](std::int64_t k, SimTime t_ns) { ticks.push_back({k, t_ns}); };
  }
};

constexpr SimTime kMinute = 60'000'000'000;

}  // namespace

TEST_CASE("PeriodicProcess: 30, 10 and 15 Hz give 1800, 600 and 900 ticks in 60 s", "[core]") {
  struct Case {
    double rate_hz;
    std::size_t expected;
  };
  for (const Case& c : {Case{30, 1800}, Case{10, 600}, Case{15, 900}}) {
    CAPTURE(c.rate_hz);
    Simulator sim;
    Recorder rec;
    PeriodicProcess process(c.rate_hz, 0.0, rec.callback());
    process.Start(sim, 0, kMinute);
    sim.Run();
    REQUIRE(rec.ticks.size() == c.expected);
    for (std::size_t i = 0; i < rec.ticks.size(); ++i) {
      REQUIRE(rec.ticks[i].k == static_cast<std::int64_t>(i));
      // round(k * 1e9 / rate) in exact integer arithmetic.
      const auto rate = static_cast<std::int64_t>(c.rate_hz);
      const std::int64_t k = rec.ticks[i].k;
      REQUIRE(rec.ticks[i].t_ns == (2 * k * 1'000'000'000 + rate) / (2 * rate));
    }
    CHECK(rec.ticks.front().t_ns == 0);
    CHECK(rec.ticks.back().t_ns < kMinute);
    CHECK_FALSE(process.running());
  }
  // The exclusive end: 10 Hz has a tick exactly at 60 s, which does not fire.
  Simulator sim;
  PeriodicProcess process(10, 0.0, [](std::int64_t, SimTime) {});
  CHECK(process.NominalTime(600) == kMinute);
  CHECK(process.NominalTime(599) == 59'900'000'000);
  PeriodicProcess camera(30, 0.0, [](std::int64_t, SimTime) {});
  CHECK(camera.NominalTime(1799) == 59'966'666'667);  // 1799e9 / 30 = 59966666666.67
  CHECK(camera.NominalTime(1) == 33'333'333);
  CHECK(camera.NominalTime(2) == 66'666'667);
}

TEST_CASE("PeriodicProcess: phase offsets shift the grid by a whole number of ticks", "[core]") {
  // Ticks at phase + k / rate < 60 s: k < (60 - phase) * rate, so the count is
  // ceil((60 - phase) * rate). The phases keep that product clear of integers
  // by more than the nanosecond rounding.
  struct Case {
    double rate_hz;
    double phase_s;
    std::size_t expected;  // ceil((60 - phase_s) * rate_hz)
  };
  const Case cases[] = {
      {30, 0.010, 1800},  // 1799.7
      {30, 0.050, 1799},  // 1798.5
      {30, 1.001, 1770},  // 1769.97
      {10, 0.025, 600},   // 599.75
      {10, 0.250, 598},   // 597.5
      {15, 0.030, 900},   // 899.55
      {15, 0.070, 899},   // 898.95
      {15, 7.000, 795},   // 795 exactly: the tick at 60 s is excluded
  };
  for (const Case& c : cases) {
    CAPTURE(c.rate_hz, c.phase_s);
    Simulator sim;
    Recorder rec;
    PeriodicProcess process(c.rate_hz, c.phase_s, rec.callback());
    process.Start(sim, 0, kMinute);
    sim.Run();
    REQUIRE(rec.ticks.size() == c.expected);
    CHECK(rec.ticks.front().k == 0);
    CHECK(rec.ticks.front().t_ns == Seconds(c.phase_s));
    CHECK(rec.ticks.back().t_ns < kMinute);
  }
}

TEST_CASE("PeriodicProcess: a window from t_start up to t_stop includes its start only", "[core]") {
  Simulator sim;
  Recorder rec;
  PeriodicProcess process(30, 0.0, rec.callback());
  process.Start(sim, Seconds(10), Seconds(20));
  sim.Run();
  REQUIRE(rec.ticks.size() == 300);
  CHECK(rec.ticks.front().k == 300);
  CHECK(rec.ticks.front().t_ns == Seconds(10));  // a tick exactly at t_start fires
  CHECK(rec.ticks.back().k == 599);

  // Starting between ticks: the first is the next one on the absolute grid.
  Recorder late;
  PeriodicProcess other(30, 0.0, late.callback());
  other.Start(sim, Seconds(30.01), Seconds(40));
  sim.Run();
  REQUIRE(late.ticks.size() == 299);
  CHECK(late.ticks.front().k == 901);
  CHECK(late.ticks.front().t_ns == 30'033'333'333);

  // An empty window fires nothing.
  Recorder none;
  PeriodicProcess empty(30, 0.0, none.callback());
  empty.Start(sim, Seconds(50), Seconds(50));
  CHECK_FALSE(empty.running());
  sim.Run();
  CHECK(none.ticks.empty());
}

TEST_CASE("PeriodicProcess: Stop from inside the callback and restart on the same grid", "[core]") {
  Simulator sim;
  std::vector<Tick> ticks;
  PeriodicProcess* self = nullptr;
  PeriodicProcess process(10, 0.05, [&](std::int64_t k, SimTime t_ns) {
    ticks.push_back({k, t_ns});
    CHECK(self->running() == (k != 14));  // 14 is the last tick of the second window
    if (k == 4) self->Stop();
  });
  self = &process;
  process.Start(sim, 0);  // no end
  CHECK(process.running());
  sim.Run();
  REQUIRE(ticks.size() == 5);
  CHECK(ticks.back().t_ns == 450'000'000);
  CHECK_FALSE(process.running());
  CHECK(sim.pending() == 0);

  // Restarting later resumes the absolute grid: tick 12 is at 1.25 s.
  sim.RunUntil(Seconds(1.2));
  process.Start(sim, sim.Now(), Seconds(1.5));
  sim.Run();
  REQUIRE(ticks.size() == 8);
  CHECK(ticks[5].k == 12);
  CHECK(ticks[5].t_ns == 1'250'000'000);
  CHECK(ticks[7].k == 14);
}

TEST_CASE("PeriodicProcess: Stop from another event, restart, and destruction cancel ticks",
          "[core]") {
  Simulator sim;
  Recorder rec;
  PeriodicProcess process(100, 0.0, rec.callback());
  process.Start(sim, 0, Seconds(1));
  // Scheduled before tick 10 (also at 0.1 s) is, so it runs first and cancels it.
  sim.ScheduleAt(Seconds(0.1), [&] { process.Stop(); });
  sim.Run();
  CHECK(rec.ticks.size() == 10);
  process.Stop();  // again: harmless

  // Start while running restarts: only one tick chain exists.
  Recorder twice;
  PeriodicProcess restarted(100, 0.0, twice.callback());
  restarted.Start(sim, Seconds(2), Seconds(3));
  restarted.Start(sim, Seconds(2), Seconds(3));
  sim.Run();
  CHECK(twice.ticks.size() == 100);

  {
    PeriodicProcess doomed(100, 0.0, [](std::int64_t, SimTime) { FAIL("tick after destruction"); });
    doomed.Start(sim, Seconds(5));
    CHECK(sim.pending() == 1);
  }
  CHECK(sim.pending() == 0);
  sim.Run();
}

TEST_CASE("PeriodicProcess: invalid arguments throw", "[core]") {
  auto noop = [](std::int64_t, SimTime) {};
  CHECK_THROWS_MATCHES(
      PeriodicProcess(0, 0, noop), std::invalid_argument,
      Catch::Message("PeriodicProcess: rate_hz (0) must be a finite value in (0, 1e9]"));
  CHECK_THROWS_AS(PeriodicProcess(-30, 0, noop), std::invalid_argument);
  CHECK_THROWS_AS(PeriodicProcess(std::nan(""), 0, noop), std::invalid_argument);
  CHECK_THROWS_AS(PeriodicProcess(INFINITY, 0, noop), std::invalid_argument);
  CHECK_THROWS_AS(PeriodicProcess(2e9, 0, noop), std::invalid_argument);
  CHECK_THROWS_MATCHES(
      PeriodicProcess(30, -0.5, noop), std::invalid_argument,
      Catch::Message("PeriodicProcess: phase_s (-0.5) must be a finite value in [0, 4.6e9]"));
  CHECK_THROWS_MATCHES(
      PeriodicProcess(30, 0, -1e-3, RngStream(1), noop), std::invalid_argument,
      Catch::Message("PeriodicProcess: jitter_s (-0.001) must be a finite value >= 0"));
  CHECK_THROWS_MATCHES(PeriodicProcess(30, 0, nullptr), std::invalid_argument,
                       Catch::Message("PeriodicProcess: the callback is empty"));

  Simulator sim;
  sim.RunUntil(100);
  PeriodicProcess process(30, 0, noop);
  CHECK_THROWS_MATCHES(
      process.Start(sim, 99), std::invalid_argument,
      Catch::Message("PeriodicProcess::Start: t_start (99 ns) is before Now() = 100 ns"));
  CHECK_THROWS_MATCHES(
      process.Start(sim, 200, 150), std::invalid_argument,
      Catch::Message("PeriodicProcess::Start: t_stop (150 ns) is before t_start (200 ns)"));
  CHECK_FALSE(process.running());
}

TEST_CASE("PeriodicProcess: jitter has the requested std, keeps order and does not accumulate",
          "[core]") {
  constexpr double kRateHz = 100.0;
  constexpr double kJitterS = 1e-3;
  constexpr SimTime kEnd = 1000'000'000'000;  // 1000 s: 100000 ticks
  Simulator sim;
  Recorder rec;
  PeriodicProcess process(kRateHz, 0.0, kJitterS, RngStream(42, "clock"), rec.callback());
  process.Start(sim, 0, kEnd);
  sim.Run();
  REQUIRE(rec.ticks.size() == 100000);

  std::vector<double> error_s(rec.ticks.size());
  for (std::size_t i = 0; i < rec.ticks.size(); ++i) {
    const Tick& tick = rec.ticks[i];
    REQUIRE(tick.k == static_cast<std::int64_t>(i));
    REQUIRE(tick.t_ns >= 0);
    REQUIRE(tick.t_ns < kEnd);
    if (i > 0) REQUIRE(tick.t_ns >= rec.ticks[i - 1].t_ns);
    // Nominal time k / 100 Hz = k * 10 ms, independently of NominalTime.
    error_s[i] = uavsim::core::ToSeconds(tick.t_ns - tick.k * 10'000'000);
    REQUIRE(std::abs(error_s[i]) < 6 * kJitterS);
  }
  auto rms = [&](std::size_t begin, std::size_t end) {
    double sum = 0.0;
    for (std::size_t i = begin; i < end; ++i) sum += error_s[i] * error_s[i];
    return std::sqrt(sum / static_cast<double>(end - begin));
  };
  double mean = 0.0;
  for (double e : error_s) mean += e;
  mean /= static_cast<double>(error_s.size());
  const double n = static_cast<double>(error_s.size());
  // Sampling tolerances: the mean has std jitter / sqrt(n) (3.2 us); the std
  // estimate has relative std 1 / sqrt(2 n) (0.22 %) over all ticks and 2.2 %
  // over 1000 ticks.
  CHECK(std::abs(mean) < 4 * kJitterS / std::sqrt(n));
  CHECK(rms(0, error_s.size()) == Approx(kJitterS).epsilon(0.01));
  // No accumulation: a random walk would make late errors ~sqrt(k) larger.
  CHECK(rms(1, 1001) == Approx(kJitterS).epsilon(0.1));
  CHECK(rms(99000, 100000) == Approx(kJitterS).epsilon(0.1));
  CHECK(std::abs(error_s[1000]) < 5 * kJitterS);
  CHECK(std::abs(error_s[99999]) < 5 * kJitterS);
}

TEST_CASE("PeriodicProcess: a tick's jitter depends only on the stream key and k", "[core]") {
  Simulator sim;
  Recorder whole, second_half, other_key;
  const RngStream rng(7, "camera/clock");
  PeriodicProcess a(30, 0.0, 2e-3, rng, whole.callback());
  PeriodicProcess b(30, 0.0, 2e-3, rng, second_half.callback());
  PeriodicProcess c(30, 0.0, 2e-3, RngStream(8, "camera/clock"), other_key.callback());
  a.Start(sim, 0, Seconds(20));
  b.Start(sim, Seconds(10), Seconds(20));
  c.Start(sim, 0, Seconds(20));
  sim.Run();
  REQUIRE(whole.ticks.size() == 600);
  REQUIRE(second_half.ticks.size() == 300);
  REQUIRE(other_key.ticks.size() == 600);
  // Away from b's window start (where its first tick may be clamped), the
  // delivered times agree tick for tick.
  int same_as_other_key = 0;
  for (std::size_t i = 1; i < second_half.ticks.size(); ++i) {
    const Tick& late = second_half.ticks[i];
    REQUIRE(whole.ticks[late.k].t_ns == late.t_ns);
  }
  for (std::size_t i = 0; i < whole.ticks.size(); ++i) {
    same_as_other_key += whole.ticks[i].t_ns == other_key.ticks[i].t_ns;
  }
  CHECK(same_as_other_key < 10);
}

TEST_CASE("PeriodicProcess: jitter larger than the period keeps ticks ordered in the window",
          "[core]") {
  Simulator sim;
  Recorder rec;
  // 50 ms of jitter on a 10 ms period: the clamps do real work here.
  PeriodicProcess process(100, 0.003, 50e-3, RngStream(3, "bad clock"), rec.callback());
  const SimTime start = Seconds(2), stop = Seconds(12);
  sim.RunUntil(start);
  process.Start(sim, start, stop);
  sim.Run();
  REQUIRE(rec.ticks.size() == 1000);  // nominal ticks 2.003 s .. 11.993 s
  CHECK(rec.ticks.front().k == 200);
  for (std::size_t i = 0; i < rec.ticks.size(); ++i) {
    REQUIRE(rec.ticks[i].t_ns >= start);
    REQUIRE(rec.ticks[i].t_ns < stop);
    if (i > 0) REQUIRE(rec.ticks[i].t_ns >= rec.ticks[i - 1].t_ns);
  }
}

TEST_CASE("PeriodicProcess: next_delivery and delivery_after_next foretell the ticks delivered",
          "[core]") {
  // Every tick's delivery, as seen from inside the callback two ticks
  // earlier, must be the delivery that then happens: with jitter whose
  // clamps work (50 ms on a 10 ms period), without jitter, and at the
  // window's end (no tick beyond it is foretold).
  for (const double jitter_s : {0.0, 2e-3, 50e-3}) {
    Simulator sim;
    std::vector<SimTime> delivered;
    std::vector<std::optional<SimTime>> next, after_next;
    PeriodicProcess* self = nullptr;
    PeriodicProcess process(100, 0.003, jitter_s, RngStream(5, "clock"),
                            [&](std::int64_t, SimTime t_ns) {
                              delivered.push_back(t_ns);
                              next.push_back(self->next_delivery());
                              after_next.push_back(self->delivery_after_next());
                            });
    self = &process;
    const SimTime start = Seconds(1), stop = Seconds(3);
    sim.RunUntil(start);
    process.Start(sim, start, stop);
    REQUIRE(process.next_delivery().has_value());
    const SimTime first = *process.next_delivery();
    const std::optional<SimTime> second = process.delivery_after_next();
    sim.Run();
    INFO("jitter " << jitter_s << " s");
    REQUIRE(delivered.size() == 200);
    CHECK(first == delivered[0]);
    REQUIRE(second.has_value());
    CHECK(*second == delivered[1]);
    for (std::size_t i = 0; i < delivered.size(); ++i) {
      if (i + 1 < delivered.size()) {
        REQUIRE(next[i].has_value());
        CHECK(*next[i] == delivered[i + 1]);
      } else {
        CHECK(!next[i].has_value());
      }
      if (i + 2 < delivered.size()) {
        REQUIRE(after_next[i].has_value());
        CHECK(*after_next[i] == delivered[i + 2]);
      } else {
        CHECK(!after_next[i].has_value());
      }
    }
  }
}
