// FMCW radar parameters (defaults: a TI AWR1843-class 77 GHz radar). The
// slope is bandwidth / chirp duration; the ADC samples sample_rate * the
// sampling window; the virtual array is nx by ny elements. The formulas the
// scattering, rain and noise keys enter are in sensors/fmcw_radar.h.
#pragma once

#include <cstdint>

#include "core/pose.h"
#include "core/rain_attenuation.h"
#include "sensors/frame_timing.h"
#include "sensors/radar_processing_config.h"

namespace uavsim::sensors {

// How one radar class of surface backscatters (fmcw_radar.h, "RCS"): a
// diffuse constant-gamma term plus a geometric-optics specular lobe.
struct RadarSurfaceConfig {
  double gamma_db = -10.0;           // diffuse: sigma0 = gamma cos(incidence)
  double fresnel_reflectance = 0.0;  // |Gamma(0)|^2, power reflectance at normal incidence
  double rms_slope = 0.3;            // of the surface roughness; sets the specular lobe's width
};

// Defaults per core::RadarClass (fmcw_radar.h cites the values).
struct RadarSurfacesConfig {
  RadarSurfaceConfig ground{-15.0, 0.06, 0.3};
  RadarSurfaceConfig concrete{-12.0, 0.15, 0.15};
  RadarSurfaceConfig glass{-25.0, 0.19, 0.03};
  RadarSurfaceConfig metal{-15.0, 1.0, 0.1};
  RadarSurfaceConfig vegetation{-10.0, 0.0, 0.3};
  RadarSurfaceConfig drone{-5.0, 0.0, 0.3};  // ~0.04 m^2 for the 0.5 m default quadrotor
  RadarSurfaceConfig bird{-7.0, 0.0, 0.3};   // 0.001-0.01 m^2 for a pigeon-to-gull mesh
};

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
  double ray_density_deg = 0.25;  // angular step of the scatterer-finding rays

  // Scatterers (FindScatterers).
  RadarSurfacesConfig surfaces;  // "surfaces": RCS model per radar class
  // A ray that hits a moving object (UAV, bird) has its cell and the eight
  // around it re-cast with rays this far apart at the hit's range (at most
  // 64 x 64 a cell), so a small object's RCS does not depend on how the
  // coarse grid falls on it.
  double object_ray_spacing_m = 0.02;
  // Scatterers are merged within cells of this fraction of the range,
  // angle (direction cosine) and velocity resolutions.
  double merge_cell_fraction = 1.0;
  // Single-bounce ground multipath of moving objects (ground plane z = 0).
  bool multipath = false;
  double multipath_reflection = 0.3;  // |Gamma| of the ground, amplitude

  // Signal (Synthesize).
  bool thermal_noise = true;  // false: the noiseless cube (tests)
  // Rain attenuation gamma = k R^alpha dB/km: k and alpha from ITU-R P.838-3
  // at carrier_ghz for this polarisation on a horizontal path
  // (core/rain_attenuation.h).
  core::Polarization polarization = core::Polarization::kHorizontal;
  // Rain clutter: volume reflectivity eta = coefficient R^exponent m^2/m^3
  // (R in mm/h) from rain_clutter_min_range_m out. The defaults are the Mie
  // backscatter of Marshall-Palmer rain at 77 GHz (fmcw_radar.h); the
  // textbook Rayleigh law at 77 GHz is 2.46e-4 R^1.6.
  bool rain_clutter = true;
  double rain_clutter_eta_coefficient = 4.07e-4;
  double rain_clutter_eta_exponent = 0.79;
  double rain_clutter_min_range_m = 1.0;

  RadarProcessingConfig processing;  // "processing": the node's signal processing

  double RaysPerFrame() const;
  // The complex IF cube: samples x chirps x virtual antennas, complex float32.
  double RawBytesPerFrame() const { return 8.0 * adc_samples * chirps_per_frame * nx * ny; }
};

template <class V>
void Visit(V& v, RadarSurfaceConfig& c);
template <class V>
void Visit(V& v, RadarSurfacesConfig& c);
template <class V>
void Visit(V& v, FmcwRadarConfig& c);

}  // namespace uavsim::sensors
