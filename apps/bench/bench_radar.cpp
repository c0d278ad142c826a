#include "apps/bench/bench_radar.h"

#include <tbb/global_control.h>

#include <functional>
#include <iomanip>
#include <string>

#include "apps/bench/gbench.h"
#include "sensors/fmcw_radar.h"
#include "sensors/radar_processor.h"
#include "sim/world_model.h"

namespace uavsim::sim {
namespace {

constexpr double kMinTimeS = 0.5;

// Wall milliseconds per call of `body`, timed by Google Benchmark for at
// least kMinTimeS (its first, discarded runs warm up).
double MillisecondsPerCall(const std::string& name, const std::function<void()>& body) {
  gbench::Register(name,
                   [&body](benchmark::State& state) {
                     for (auto _ : state) body();
                   })
      ->Unit(benchmark::kMillisecond)
      ->MinTime(kMinTimeS);
  return gbench::RunSingle().Fastest().real_s_per_iteration * 1e3;
}

}  // namespace

int BenchRadar(bool quiet, std::ostream& out) {
  const Scenario s;
  WorldModel world(s);
  const NodeConfig* node = nullptr;
  for (const auto& n : s.nodes)
    if (n.sensor.type == sensors::SensorType::kFmcwRadar) node = &n;
  sensors::FmcwRadar radar(node->sensor.radar, world.scene());
  sensors::RadarProcessor processor(node->sensor.radar);
  const double t_s = 10.0;
  world.scene().SetTime(t_s);
  const std::vector<sensors::BoundingSphere> uav{
      {world.target().StateAt(t_s).position_m, world.uav_radius_m(0)}};
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  if (!quiet)
    out << "default radar (" << node->sensor.radar.adc_samples << " samples x "
        << node->sensor.radar.chirps_per_frame << " chirps x "
        << node->sensor.radar.nx * node->sensor.radar.ny << " antennas), one thread, t = 10 s\n";
  out << std::left << std::setw(12) << "weather" << std::right << std::setw(12) << "scatterers"
      << std::setw(14) << "find ms" << std::setw(18) << "find ms, no cache" << std::setw(14)
      << "synth ms" << std::setw(19) << "synth ms, no cache" << std::setw(14) << "process ms"
      << std::setw(14) << "frames/s"
      << "\n";
  sensors::FmcwRadar uncached(node->sensor.radar, world.scene());
  uncached.set_static_cache(false);
  for (double rain : {0.0, 25.0}) {
    core::WeatherConfig weather;
    weather.rain_mm_h = rain;
    core::RngStream noise(1, "bench/radar");
    std::vector<sensors::Scatterer> scatterers;
    sensors::RadarCube cube;
    const double find_ms =
        MillisecondsPerCall("find", [&] { scatterers = radar.FindScatterers(t_s, uav); });
    const double uncached_ms = MillisecondsPerCall(
        "find, no cache", [&] { benchmark::DoNotOptimize(uncached.FindScatterers(t_s, uav)); });
    const double synth_ms =
        MillisecondsPerCall("synth", [&] { cube = radar.Synthesize(scatterers, weather, noise); });
    // The static world's sums made every frame (frames/s is the cached radar's).
    core::RngStream noise_uncached(1, "bench/radar");
    const double synth_uncached_ms = MillisecondsPerCall("synth, no cache", [&] {
      benchmark::DoNotOptimize(uncached.Synthesize(scatterers, weather, noise_uncached));
    });
    const double proc_ms = MillisecondsPerCall(
        "process", [&] { benchmark::DoNotOptimize(processor.Process(cube, radar.X_WR(), t_s)); });
    out << std::left << std::setw(12) << (rain > 0 ? "rain 25" : "dry") << std::right
        << std::setw(12) << scatterers.size() << std::fixed << std::setprecision(2) << std::setw(14)
        << find_ms << std::setw(18) << uncached_ms << std::setw(14) << synth_ms << std::setw(19)
        << synth_uncached_ms << std::setw(14) << proc_ms << std::setw(14)
        << 1000.0 / (find_ms + synth_ms + proc_ms) << std::defaultfloat << "\n"
        << std::flush;
  }
  return 0;
}

}  // namespace uavsim::sim
