#include "pipeline/node/preprocess_config.h"

#include "core/json_io.h"

namespace uavsim::pipeline {

using core::Rule;

template <class V>
void Visit(V& v, CameraPreprocessConfig& c) {
  v("raw", c.raw);
  v("rectified_width_px", c.rectified_width_px, Rule::Range(16, 8192));
  v("rectified_height_px", c.rectified_height_px, Rule::Range(16, 8192));
  v("rectified_focal_px", c.rectified_focal_px, Rule::Positive(1e5));
  v("warmup_frames", c.warmup_frames, Rule::Range(0, 100000));
  v("mog2_history_frames", c.mog2_history_frames, Rule::Range(1, 100000));
  v("mog2_var_threshold", c.mog2_var_threshold, Rule::Positive(1e4));
  v("morphology_kernel_px", c.morphology_kernel_px, Rule::Range(1, 31));
  v("min_blob_area_px", c.min_blob_area_px, Rule::Range(1, 1000000));
  v("gate_px", c.gate_px, Rule::NonNegative(1e5));
  v("gate_max_age_frames", c.gate_max_age_frames, Rule::Range(1, 100000));
  v("roi_margin", c.roi_margin, Rule::Range(1.0, 100.0));
  v("min_roi_side_px", c.min_roi_side_px, Rule::Range(4.0, 8192.0));
  v("stereo_min_range_m", c.stereo_min_range_m, Rule::Positive(1e5));
  v("ncc_min", c.ncc_min, Rule::Range(-1.0, 1.0));
  v("epipolar_slack_px", c.epipolar_slack_px, Rule::Range(0, 64));
}

template <class V>
void Visit(V& v, LidarPreprocessConfig& c) {
  v("raw", c.raw);
  v.Enum("background", c.background,
         {{"warmup", LidarBackground::kWarmup}, {"survey", LidarBackground::kSurvey}});
  v("survey_coverage", c.survey_coverage, Rule{0.0, 1.0, true, false});
  v("survey_horizon_s", c.survey_horizon_s, Rule::Positive(3600.0));
  v("voxel_size_m", c.voxel_size_m, Rule::Range(0.01, 100.0));
  v("warmup_frames", c.warmup_frames, Rule::Range(1, 100000));
  v("occupancy_threshold", c.occupancy_threshold, Rule{0.0, 1.0, true, false});
  v("static_neighbourhood", c.static_neighbourhood);
  v("cluster_eps_m", c.cluster_eps_m, Rule::Positive(1000.0));
  v("cluster_min_points", c.cluster_min_points, Rule::Range(1, 100000));
  v("clusters_kept", c.clusters_kept, Rule::Range(0, 1000));
  v("weather_echo_rejection", c.weather_echo_rejection);
  v("fog_echo_margin", c.fog_echo_margin, Rule::Range(1.0, 1000.0));
  v("rain_echo_margin", c.rain_echo_margin, Rule::Range(1.0, 1000.0));
  v("drone_gate", c.drone_gate);
  v("drone_max_size_m", c.drone_max_size_m, Rule::Positive(100.0));
  v("drone_max_speed_mps", c.drone_max_speed_mps, Rule::NonNegative(1000.0));
  v("drone_count_margin", c.drone_count_margin, Rule::Positive(1e6));
}

std::vector<std::string> NodeExtensions(const PreprocessConfig& p) {
  std::vector<std::string> ext;
  if (p.lidar.weather_echo_rejection) ext.push_back("lidar.weather_echo_rejection=true");
  if (p.lidar.drone_gate) ext.push_back("lidar.drone_gate=true");
  if (p.radar.rain_doppler_rejection) ext.push_back("radar.rain_doppler_rejection=true");
  if (p.radar.min_peak_snr_db > 0.0)
    ext.push_back("radar.min_peak_snr_db=" + core::FormatNumber(p.radar.min_peak_snr_db));
  if (p.radar.selection != RadarSelection::kLargest)
    ext.push_back(std::string("radar.selection=") + RadarSelectionName(p.radar.selection));
  if (p.max_observations > 1)
    ext.push_back("max_observations=" + std::to_string(p.max_observations));
  return ext;
}

const char* LidarBackgroundName(LidarBackground b) {
  return b == LidarBackground::kWarmup ? "warmup" : "survey";
}

const char* RadarSelectionName(RadarSelection s) {
  return s == RadarSelection::kLargest ? "largest" : "persistent";
}

template <class V>
void Visit(V& v, RadarPreprocessConfig& c) {
  v("raw", c.raw);
  v("cluster_eps_m", c.cluster_eps_m, Rule::Positive(1000.0));
  v("cluster_min_points", c.cluster_min_points, Rule::Range(1, 100000));
  v("velocity_weight_s", c.velocity_weight_s, Rule::NonNegative(1000.0));
  v("clusters_kept", c.clusters_kept, Rule::Range(0, 1000));
  v.Enum("selection", c.selection,
         {{"largest", RadarSelection::kLargest}, {"persistent", RadarSelection::kPersistent}});
  v("rain_doppler_rejection", c.rain_doppler_rejection);
  v("rain_doppler_margin_mps", c.rain_doppler_margin_mps, Rule::NonNegative(100.0));
  v("persistence_frames", c.persistence_frames, Rule::Range(1, 1000));
  v("min_support", c.min_support, Rule::Range(0, 1000));
  v("gate_m", c.gate_m, Rule::Positive(1000.0));
  v("max_speed_mps", c.max_speed_mps, Rule::NonNegative(1000.0));
  v("min_peak_snr_db", c.min_peak_snr_db, Rule::NonNegative(200.0));
}

const char* NodeWeatherSourceName(NodeWeatherSource s) {
  return s == NodeWeatherSource::kTruth ? "truth" : "assumed";
}

core::WeatherConfig NodeWeatherConfig::Known(const core::WeatherConfig& truth) const {
  if (source == NodeWeatherSource::kTruth) return truth;
  core::WeatherConfig w = truth;  // illumination: no node uses it
  w.rain_mm_h = assumed_rain_mm_h;
  w.fog_visibility_m = assumed_fog_visibility_m;
  return w;
}

std::vector<std::string> NodeOracles(const PreprocessConfig& p) {
  const bool uses_weather = (p.lidar.weather_echo_rejection && !p.LidarRaw()) ||
                            (p.radar.rain_doppler_rejection && !p.RadarRaw());
  if (uses_weather && p.weather.source == NodeWeatherSource::kTruth) return {"weather=truth"};
  return {};
}

template <class V>
void Visit(V& v, NodeWeatherConfig& c) {
  v.Enum("source", c.source,
         {{"truth", NodeWeatherSource::kTruth}, {"assumed", NodeWeatherSource::kAssumed}});
  v("assumed_rain_mm_h", c.assumed_rain_mm_h, Rule::NonNegative(300.0));
  v("assumed_fog_visibility_m", c.assumed_fog_visibility_m, Rule{1.0, 1e5, false, false});
}

template <class V>
void Visit(V& v, PreprocessConfig& c) {
  v("raw", c.raw);
  v("max_observations", c.max_observations, Rule::Range(1, 64));
  v.Object("camera", c.camera);
  v.Object("lidar", c.lidar);
  v.Object("radar", c.radar);
  v.Object("weather", c.weather);
}

UAVSIM_INSTANTIATE_VISIT(CameraPreprocessConfig);
UAVSIM_INSTANTIATE_VISIT(LidarPreprocessConfig);
UAVSIM_INSTANTIATE_VISIT(RadarPreprocessConfig);
UAVSIM_INSTANTIATE_VISIT(NodeWeatherConfig);
UAVSIM_INSTANTIATE_VISIT(PreprocessConfig);

}  // namespace uavsim::pipeline
