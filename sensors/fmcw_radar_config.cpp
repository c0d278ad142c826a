#include "sensors/fmcw_radar_config.h"

#include <cmath>

#include "core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

double FmcwRadarConfig::RaysPerFrame() const {
  return std::ceil(fov_azimuth_deg / ray_density_deg) *
         std::ceil(fov_elevation_deg / ray_density_deg);
}

template <class V>
void Visit(V& v, RadarSurfaceConfig& c) {
  v("gamma_db", c.gamma_db, Rule::Range(-200.0, 20.0));
  v("fresnel_reflectance", c.fresnel_reflectance, Rule::Probability());
  v("rms_slope", c.rms_slope, Rule::Range(0.001, 10.0));
}
UAVSIM_INSTANTIATE_VISIT(RadarSurfaceConfig);

template <class V>
void Visit(V& v, RadarSurfacesConfig& c) {
  v.Object("ground", c.ground);
  v.Object("concrete", c.concrete);
  v.Object("glass", c.glass);
  v.Object("metal", c.metal);
  v.Object("vegetation", c.vegetation);
  v.Object("drone", c.drone);
  v.Object("bird", c.bird);
}
UAVSIM_INSTANTIATE_VISIT(RadarSurfacesConfig);

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
  v.Object("surfaces", c.surfaces);
  v("object_ray_spacing_m", c.object_ray_spacing_m, Rule::Range(0.001, 10.0));
  v("merge_cell_fraction", c.merge_cell_fraction, Rule::Range(0.01, 1.0));
  v("multipath", c.multipath);
  v("multipath_reflection", c.multipath_reflection, Rule::Probability());
  v("thermal_noise", c.thermal_noise);
  v.Enum("polarization", c.polarization, core::PolarizationNames());
  v("rain_clutter", c.rain_clutter);
  v("rain_clutter_eta_coefficient", c.rain_clutter_eta_coefficient, Rule::NonNegative(1.0));
  v("rain_clutter_eta_exponent", c.rain_clutter_eta_exponent, Rule::Range(0.1, 3.0));
  v("rain_clutter_min_range_m", c.rain_clutter_min_range_m, Rule::Positive(1000.0));
  v.Object("processing", c.processing);
  // The processing chain's preconditions (sensors/radar_processor.h), here
  // so that validate refuses what run could not process.
  const RadarProcessingConfig& p = c.processing;
  const int range_window = 2 * (p.cfar_guard_range_cells + p.cfar_training_range_cells) + 1;
  const int doppler_window = 2 * (p.cfar_guard_doppler_cells + p.cfar_training_doppler_cells) + 1;
  v.Check(range_window <= c.adc_samples, "adc_samples",
          "the CFAR window of processing (2 (cfar_guard_range_cells + cfar_training_range_cells) "
          "+ 1 = " +
              std::to_string(range_window) + " range cells) exceeds adc_samples (" +
              std::to_string(c.adc_samples) + ")");
  v.Check(doppler_window <= c.chirps_per_frame, "chirps_per_frame",
          "the CFAR window of processing (2 (cfar_guard_doppler_cells + "
          "cfar_training_doppler_cells) + 1 = " +
              std::to_string(doppler_window) + " Doppler cells) exceeds chirps_per_frame (" +
              std::to_string(c.chirps_per_frame) + ")");
  v.Check(p.source_count != SourceCount::kMdl || p.max_sources < c.nx * c.ny, "processing",
          "max_sources (" + std::to_string(p.max_sources) +
              ") must be below the array's nx * ny = " + std::to_string(c.nx * c.ny) +
              " elements for source_count \"mdl\"");
}
UAVSIM_INSTANTIATE_VISIT(FmcwRadarConfig);

}  // namespace uavsim::sensors
