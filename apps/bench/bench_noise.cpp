#include "apps/bench/bench_noise.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <iomanip>
#include <vector>

#include "core/counter_normal.h"
#include "core/rng.h"

namespace uavsim::sim {
namespace {

constexpr int kWidth = 640, kRowsPerFrame = 2 * 480;
constexpr int kWarmupFrames = 2, kFrames = 20, kRepetitions = 3;

// Keeps the samples observable, so the compiler cannot drop the work.
volatile float g_sink = 0.0f;

std::uint64_t RowKey(int frame, int row) {
  return core::Mix64((static_cast<std::uint64_t>(frame) << 32) | static_cast<std::uint32_t>(row));
}

// Runs `row(key, buffer)` over `frames` frames; seconds of wall time.
template <class T>
double Seconds(int frames, const std::function<void(std::uint64_t, T*)>& row) {
  std::vector<T> buffer(kWidth);
  const auto start = std::chrono::steady_clock::now();
  for (int f = 0; f < frames; ++f)
    for (int r = 0; r < kRowsPerFrame; ++r) {
      row(RowKey(f, r), buffer.data());
      g_sink = g_sink + static_cast<float>(buffer[static_cast<std::size_t>(r % kWidth)]);
    }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <class T>
double BestSeconds(const std::function<void(std::uint64_t, T*)>& row) {
  Seconds<T>(kWarmupFrames, row);
  double best = 1e300;
  for (int i = 0; i < kRepetitions; ++i) best = std::min(best, Seconds<T>(kFrames, row));
  return best;
}

struct Case {
  const char* name;
  std::function<double()> seconds;
};

}  // namespace

int BenchNoise(bool quiet, std::ostream& out) {
  const std::vector<Case> cases{
      {"RngStream::Normal, per pixel",
       [] {
         return BestSeconds<float>([](std::uint64_t key, float* row) {
           core::RngStream rng(key);
           for (int u = 0; u < kWidth; ++u) row[u] = static_cast<float>(rng.Normal());
         });
       }},
      {"CounterNormal::Fill float, per row",
       [] {
         return BestSeconds<float>(
             [](std::uint64_t key, float* row) { core::CounterNormal(key).Fill(0, row, kWidth); });
       }},
      {"CounterNormal::Fill double, per row",
       [] {
         return BestSeconds<double>(
             [](std::uint64_t key, double* row) { core::CounterNormal(key).Fill(0, row, kWidth); });
       }},
      {"CounterNormal::At, per pixel",
       [] {
         return BestSeconds<float>([](std::uint64_t key, float* row) {
           const core::CounterNormal g(key);
           for (int u = 0; u < kWidth; ++u) row[u] = static_cast<float>(g.At(u));
         });
       }},
  };
  const double samples = static_cast<double>(kFrames) * kRowsPerFrame * kWidth;
  if (!quiet)
    out << "standard normals for " << kFrames << " stereo frames (2 x 640 x 480), one key per row, "
        << "one thread; best of " << kRepetitions << " after a warm-up of " << kWarmupFrames
        << " frames\n";
  out << std::left << std::setw(38) << "case" << std::right << std::setw(10) << "M samples"
      << std::setw(9) << "seconds" << std::setw(12) << "M samples/s" << std::setw(11) << "ns/sample"
      << std::setw(10) << "speed-up" << '\n';
  double baseline_s = 0.0;
  for (const Case& c : cases) {
    const double s = c.seconds();
    if (baseline_s == 0.0) baseline_s = s;
    out << std::left << std::setw(38) << c.name << std::right << std::fixed << std::setprecision(2)
        << std::setw(10) << samples * 1e-6 << std::setprecision(3) << std::setw(9) << s
        << std::setprecision(1) << std::setw(12) << samples / s * 1e-6 << std::setprecision(2)
        << std::setw(11) << s / samples * 1e9 << std::setprecision(1) << std::setw(9)
        << baseline_s / s << "x" << std::defaultfloat << '\n'
        << std::flush;
  }
  return 0;
}

}  // namespace uavsim::sim
