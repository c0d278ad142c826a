// FMCW radar parameters (defaults: a TI AWR1843-class 77 GHz radar). The
// slope is bandwidth / chirp duration; the ADC samples sample_rate * the
// sampling window; the virtual array is nx by ny elements.
#pragma once

#include <cstdint>

#include "sensors/frame_timing.h"
#include "sensors/radar_processing_config.h"
#include "sim/core/pose.h"

namespace uavsim::sensors {

struct FmcwRadarConfig {
  FrameTiming timing{15.0};  // paper: f_r = 15 Hz
  core::PoseConfig pose;
  double carrier_ghz = 77.0;
  double bandwidth_mhz = 900.0;  // range resolution c / 2B = 0.167 m
  double chirp_duration_us = 60.0;
  double idle_time_us = 20.0;
  int adc_samples = 512;
  double sample_rate_msps = 10.0;  // max range fs c / 2K = 100 m
  int chirps_per_frame = 64;
  double tx_power_dbm = 12.0;
  double antenna_gain_dbi = 10.0;
  double noise_figure_db = 12.0;
  int nx = 4;
  int ny = 3;
  double spacing_x_wavelengths = 0.5;
  double spacing_y_wavelengths = 0.5;
  double fov_azimuth_deg = 120.0;
  double fov_elevation_deg = 60.0;
  double ray_density_deg = 0.25;     // angular step of the scatterer-finding rays
  RadarProcessingConfig processing;  // "processing": the node's signal processing

  double RaysPerFrame() const;
  // The complex IF cube: samples x chirps x virtual antennas, complex float32.
  double RawBytesPerFrame() const { return 8.0 * adc_samples * chirps_per_frame * nx * ny; }
};

template <class V>
void Visit(V& v, FmcwRadarConfig& c);

}  // namespace uavsim::sensors
