#include "apps/bench/bench_noise.h"

#include <cstdint>
#include <functional>
#include <iomanip>
#include <utility>
#include <vector>

#include "apps/bench/gbench.h"
#include "core/counter_normal.h"
#include "core/rng.h"

namespace uavsim::sim {
namespace {

constexpr int kWidth = 640, kRowsPerFrame = 2 * 480;
constexpr double kSamplesPerFrame = static_cast<double>(kWidth) * kRowsPerFrame;
constexpr double kWarmUpS = 0.02, kMinTimeS = 0.1;
constexpr int kRepetitions = 3;

std::uint64_t RowKey(int frame, int row) {
  return core::Mix64((static_cast<std::uint64_t>(frame) << 32) | static_cast<std::uint32_t>(row));
}

// One Google Benchmark iteration = one frame: `row(key, buffer)` for each of
// its rows. Every run starts again at frame 0, so it draws the same numbers.
template <class T>
std::function<void(benchmark::State&)> Frames(std::function<void(std::uint64_t, T*)> row) {
  return [row = std::move(row)](benchmark::State& state) {
    std::vector<T> buffer(kWidth);
    int frame = 0;
    for (auto _ : state) {
      for (int r = 0; r < kRowsPerFrame; ++r) {
        row(RowKey(frame, r), buffer.data());
        // The samples count as read, so the compiler cannot drop the work.
        benchmark::DoNotOptimize(buffer.data());
        benchmark::ClobberMemory();
      }
      ++frame;
    }
    state.counters["samples"] =
        benchmark::Counter(kSamplesPerFrame, benchmark::Counter::kIsIterationInvariantRate);
  };
}

struct Case {
  const char* name;
  std::function<void(benchmark::State&)> body;
};

std::vector<Case> Cases() {
  return {
      {"RngStream::Normal, per pixel", Frames<float>([](std::uint64_t key, float* row) {
         core::RngStream rng(key);
         for (int u = 0; u < kWidth; ++u) row[u] = static_cast<float>(rng.Normal());
       })},
      {"CounterNormal::Fill float, per row", Frames<float>([](std::uint64_t key, float* row) {
         core::CounterNormal(key).Fill(0, row, kWidth);
       })},
      {"CounterNormal::Fill double, per row", Frames<double>([](std::uint64_t key, double* row) {
         core::CounterNormal(key).Fill(0, row, kWidth);
       })},
      {"CounterNormal::At, per pixel", Frames<float>([](std::uint64_t key, float* row) {
         const core::CounterNormal g(key);
         for (int u = 0; u < kWidth; ++u) row[u] = static_cast<float>(g.At(u));
       })},
  };
}

}  // namespace

int BenchNoise(bool quiet, std::ostream& out) {
  if (!quiet)
    out << "standard normals for stereo frames (2 x 640 x 480), one key per row, one thread; "
        << "Google Benchmark, frames for >= " << kMinTimeS << " s after a warm-up of " << kWarmUpS
        << " s, best of " << kRepetitions << " repetitions\n";
  out << std::left << std::setw(38) << "case" << std::right << std::setw(10) << "M samples"
      << std::setw(9) << "seconds" << std::setw(12) << "M samples/s" << std::setw(11) << "ns/sample"
      << std::setw(10) << "speed-up" << '\n';
  double baseline_per_s = 0.0;
  for (const Case& c : Cases()) {
    gbench::Register(c.name, c.body)
        ->Unit(benchmark::kMillisecond)
        ->MinWarmUpTime(kWarmUpS)
        ->MinTime(kMinTimeS)
        ->Repetitions(kRepetitions);
    const gbench::Measurement m = gbench::RunSingle().Fastest();
    const double samples = kSamplesPerFrame * static_cast<double>(m.iterations);
    const double per_s = m.Counter("samples");
    if (baseline_per_s == 0.0) baseline_per_s = per_s;
    out << std::left << std::setw(38) << c.name << std::right << std::fixed << std::setprecision(2)
        << std::setw(10) << samples * 1e-6 << std::setprecision(3) << std::setw(9) << m.seconds()
        << std::setprecision(1) << std::setw(12) << per_s * 1e-6 << std::setprecision(2)
        << std::setw(11) << 1e9 / per_s << std::setprecision(1) << std::setw(9)
        << per_s / baseline_per_s << "x" << std::defaultfloat << '\n'
        << std::flush;
  }
  return 0;
}

}  // namespace uavsim::sim
