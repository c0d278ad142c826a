#include "sensors/sensor_config.h"

#include <cmath>

#include "sim/core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

template <class V>
void VisitTiming(V& v, FrameTiming& c) {
  v("rate_hz", c.rate_hz, Rule::Positive(10000.0));
  v("phase_s", c.phase_s, Rule::NonNegative(3600.0));
  v("clock_jitter_s", c.clock_jitter_s, Rule::NonNegative(1.0));
  v.Check(c.clock_jitter_s < 0.5 / c.rate_hz, "clock_jitter_s",
          "clock_jitter_s must be below half a frame period (" +
              core::FormatNumber(0.5 / c.rate_hz) + " s)");
}

template <class V>
void Visit(V& v, FisheyeStereoConfig& c) {
  VisitTiming(v, c.timing);
  v.Object("pose", c.pose);
  v("width_px", c.width_px, Rule::Range(16, 8192));
  v("height_px", c.height_px, Rule::Range(16, 8192));
  v("xi", c.xi, Rule::Range(0.0, 10.0));
  v("fx_px", c.fx_px, Rule::Positive(1e5));
  v("fy_px", c.fy_px, Rule::Positive(1e5));
  v("cx_px", c.cx_px, Rule::Range(0.0, 8192.0));
  v("cy_px", c.cy_px, Rule::Range(0.0, 8192.0));
  v.Check(c.cx_px <= c.width_px, "cx_px",
          "cx_px must lie inside the image (width_px " + std::to_string(c.width_px) + ")");
  v.Check(c.cy_px <= c.height_px, "cy_px",
          "cy_px must lie inside the image (height_px " + std::to_string(c.height_px) + ")");
  v("k1", c.k1, Rule::Range(-10.0, 10.0));
  v("k2", c.k2, Rule::Range(-10.0, 10.0));
  v("p1", c.p1, Rule::Range(-1.0, 1.0));
  v("p2", c.p2, Rule::Range(-1.0, 1.0));
  v("k3", c.k3, Rule::Range(-10.0, 10.0));
  v("baseline_m", c.baseline_m, Rule::Positive(10.0));
}
UAVSIM_INSTANTIATE_VISIT(FisheyeStereoConfig);

double LidarConfig::RaysPerFrame() const {
  if (preset == LidarPreset::kLivoxRosette) return std::ceil(points_per_s / timing.rate_hz);
  return channels * std::ceil(360.0 / azimuth_resolution_deg);
}

template <class V>
void Visit(V& v, LidarConfig& c) {
  VisitTiming(v, c.timing);
  v.Object("pose", c.pose);
  v.Enum("preset", c.preset,
         {{"spinning32", LidarPreset::kSpinning32}, {"livox_rosette", LidarPreset::kLivoxRosette}});
  if (c.preset == LidarPreset::kSpinning32) {
    v("channels", c.channels, Rule::Range(1, 128));
    v("vertical_min_deg", c.vertical_min_deg, Rule::Range(-90.0, 90.0));
    v("vertical_max_deg", c.vertical_max_deg, Rule::Range(-90.0, 90.0));
    v.Check(c.vertical_min_deg < c.vertical_max_deg, "vertical_max_deg",
            "vertical_max_deg must be above vertical_min_deg");
    v("azimuth_resolution_deg", c.azimuth_resolution_deg, Rule::Range(0.001, 45.0));
  } else {
    v("points_per_s", c.points_per_s, Rule::Positive(1e9));
    v("fov_deg", c.fov_deg, Rule{0.0, 180.0, true, false});
  }
  v("max_range_m", c.max_range_m, Rule::Positive(10000.0));
  v("range_noise_m", c.range_noise_m, Rule::NonNegative(10.0));
  v("dropout", c.dropout, Rule{0.0, 1.0, false, true});
}
UAVSIM_INSTANTIATE_VISIT(LidarConfig);

double FmcwRadarConfig::RaysPerFrame() const {
  return std::ceil(fov_azimuth_deg / ray_density_deg) *
         std::ceil(fov_elevation_deg / ray_density_deg);
}

template <class V>
void Visit(V& v, FmcwRadarConfig& c) {
  VisitTiming(v, c.timing);
  v.Object("pose", c.pose);
  v("carrier_ghz", c.carrier_ghz, Rule::Range(1.0, 300.0));
  v("bandwidth_mhz", c.bandwidth_mhz, Rule::Positive(10000.0));
  v("chirp_duration_us", c.chirp_duration_us, Rule::Positive(10000.0));
  v("idle_time_us", c.idle_time_us, Rule::NonNegative(10000.0));
  v("adc_samples", c.adc_samples, Rule::Range(8, 8192));
  v("sample_rate_msps", c.sample_rate_msps, Rule::Positive(1000.0));
  v.Check(c.adc_samples / c.sample_rate_msps <= c.chirp_duration_us, "adc_samples",
          "the ADC window adc_samples / sample_rate (" +
              core::FormatNumber(c.adc_samples / c.sample_rate_msps) +
              " us) must fit in chirp_duration_us (" + core::FormatNumber(c.chirp_duration_us) +
              ")");
  v("chirps_per_frame", c.chirps_per_frame, Rule::Range(1, 4096));
  const double chirps_s = c.chirps_per_frame * (c.chirp_duration_us + c.idle_time_us) * 1e-6;
  v.Check(chirps_s <= 1.0 / c.timing.rate_hz, "chirps_per_frame",
          "the chirps of one frame last " + core::FormatNumber(chirps_s) +
              " s, longer than the frame period (" + core::FormatNumber(1.0 / c.timing.rate_hz) +
              " s)");
  v("tx_power_dbm", c.tx_power_dbm, Rule::Range(-50.0, 60.0));
  v("antenna_gain_dbi", c.antenna_gain_dbi, Rule::Range(-20.0, 50.0));
  v("noise_figure_db", c.noise_figure_db, Rule::Range(0.0, 50.0));
  v("nx", c.nx, Rule::Range(1, 256));
  v("ny", c.ny, Rule::Range(1, 256));
  v("spacing_x_wavelengths", c.spacing_x_wavelengths, Rule::Positive(10.0));
  v("spacing_y_wavelengths", c.spacing_y_wavelengths, Rule::Positive(10.0));
  v("fov_azimuth_deg", c.fov_azimuth_deg, Rule{0.0, 360.0, true, false});
  v("fov_elevation_deg", c.fov_elevation_deg, Rule{0.0, 180.0, true, false});
  v("ray_density_deg", c.ray_density_deg, Rule::Range(0.001, 10.0));
}
UAVSIM_INSTANTIATE_VISIT(FmcwRadarConfig);

const FrameTiming& SensorConfig::timing() const {
  return WithActive([](const auto& c) -> const FrameTiming& { return c.timing; });
}

const core::PoseConfig& SensorConfig::pose() const {
  return WithActive([](const auto& c) -> const core::PoseConfig& { return c.pose; });
}

const char* SensorConfig::modality() const {
  switch (type) {
    case SensorType::kLidar:
      return "lidar";
    case SensorType::kFmcwRadar:
      return "radar";
    default:
      return "camera";
  }
}

double SensorConfig::RaysPerFrame() const {
  return WithActive([](const auto& c) { return c.RaysPerFrame(); });
}

double SensorConfig::RawBytesPerFrame() const {
  return WithActive([](const auto& c) { return c.RawBytesPerFrame(); });
}

template <class V>
void Visit(V& v, SensorConfig& c) {
  v.Enum("type", c.type,
         {{"fisheye_stereo", SensorType::kFisheyeStereo},
          {"lidar", SensorType::kLidar},
          {"fmcw_radar", SensorType::kFmcwRadar}});
  // The type's keys sit beside "type" in the same object.
  switch (c.type) {
    case SensorType::kFisheyeStereo:
      Visit(v, c.fisheye);
      break;
    case SensorType::kLidar:
      Visit(v, c.lidar);
      break;
    case SensorType::kFmcwRadar:
      Visit(v, c.radar);
      break;
  }
}
UAVSIM_INSTANTIATE_VISIT(SensorConfig);

}  // namespace uavsim::sensors
