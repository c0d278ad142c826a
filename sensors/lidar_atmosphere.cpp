#include "sensors/lidar_atmosphere.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/physical_constants.h"

namespace uavsim::sensors {

double FogExtinctionPerM(double visibility_m) {
  return FogExtinctionPerM(visibility_m, kLidarWavelengthNm);
}

double AtmosphericExtinctionPerM(const core::WeatherConfig& weather) {
  return OpticalExtinctionPerM(weather, kLidarWavelengthNm);
}

double LidarOverlap(const LidarConfig& c, double range_m) {
  if (range_m < c.min_range_m) return 0.0;
  if (range_m >= c.full_overlap_range_m) return 1.0;
  return (range_m - c.min_range_m) / (c.full_overlap_range_m - c.min_range_m);
}

double LidarThreshold(const LidarConfig& c) {
  return c.reference_reflectivity / (c.max_range_m * c.max_range_m);
}

double LidarPowerOfIntensity(const LidarConfig& c, double intensity) {
  if (intensity >= 1.0) return std::numeric_limits<double>::infinity();
  return intensity / (c.saturation_range_m * c.saturation_range_m);
}

double FogEchoMeanPower(const LidarConfig& c, const core::WeatherConfig& w, double range_m) {
  if (!w.fog_visibility_m || range_m <= 0.0) return 0.0;
  const double beta = kFogBackscatterTimesVisibility / *w.fog_visibility_m;
  const double rho_v = core::kPi * beta * core::kSpeedOfLight_mps * c.pulse_width_ns * 1e-9 / 2.0;
  const double alpha = AtmosphericExtinctionPerM(w);
  return rho_v * LidarOverlap(c, range_m) * std::exp(-2.0 * alpha * range_m) / (range_m * range_m);
}

double FogSpeckleCells(const LidarConfig& c) {
  const double n =
      c.receiver_aperture_mm * 1e-3 * c.beam_divergence_mrad * 1e-3 / (kLidarWavelengthNm * 1e-9);
  return std::max(1.0, n * n);
}

double FogSpeckleFade(double cells, core::RngStream& rng) {
  // Marsaglia & Tsang (2000), shape >= 1: accept d v with v = (1 + c x)^3.
  const double d = cells - 1.0 / 3.0;
  const double c = 1.0 / std::sqrt(9.0 * d);
  for (;;) {
    const double x = rng.Normal();
    const double t = 1.0 + c * x;
    if (t <= 0.0) continue;
    const double v = t * t * t;
    const double u = rng.Uniform();
    if (u < 1.0 - 0.0331 * x * x * x * x || std::log(u) < 0.5 * x * x + d * (1.0 - v + std::log(v)))
      return d * v / cells;
  }
}

double RainEchoMaxPower(const LidarConfig& c, const core::WeatherConfig& w, double range_m) {
  if (!(w.rain_mm_h > 0.0) || range_m <= 0.0) return 0.0;
  const double alpha = AtmosphericExtinctionPerM(w);
  return kWaterFresnel * LidarOverlap(c, range_m) * std::exp(-2.0 * alpha * range_m) /
         (range_m * range_m);
}

}  // namespace uavsim::sensors
