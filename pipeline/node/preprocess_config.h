// Sensing-node pre-processing parameters (paper Sec. IV-A), one object per
// modality under the scenario's /pipeline/preprocess. The processing itself
// and the meaning of each key are in camera_preprocessor.h,
// lidar_preprocessor.h and radar_preprocessor.h.
//
// Ablations (paper Sec. VI, "without preprocessing" and the camera-only
// table): `raw` switches every modality to its raw variant; a modality's own
// `raw` switches only that one.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/weather.h"

namespace uavsim::pipeline {

struct CameraPreprocessConfig {
  bool raw = false;
  // Rectified pinhole view of each eye (same orientation as the eye, so the
  // stereo pair is row-aligned). Principal point at the image centre.
  int rectified_width_px = 640;
  int rectified_height_px = 480;
  // null: fx_px / (1 + xi), the fisheye's own scale at its centre (no
  // magnification of the central pixels).
  std::optional<double> rectified_focal_px;
  // Background subtraction (OpenCV MOG2) on the rectified left eye. No
  // detection is reported during the first warmup_frames frames.
  int warmup_frames = 15;
  int mog2_history_frames = 300;
  double mog2_var_threshold = 16.0;  // squared Mahalanobis distance to the background model
  int morphology_kernel_px = 3;      // closing (joins a target's fragments); 1: none
  // After closing. A 0.5 m UAV at 70 m is about one rectified pixel; MOG2's
  // per-pixel variance and the stereo check (ncc_min) reject sensor noise.
  int min_blob_area_px = 1;
  // Prefer the largest blob within gate_px of the previous detection (made
  // within the last gate_max_age_frames frames); 0: no gate.
  double gate_px = 50.0;
  int gate_max_age_frames = 15;
  // ROI: a square of side max(min_roi_side_px, roi_margin * blob extent).
  double roi_margin = 3.0;
  double min_roi_side_px = 32.0;
  // Right eye: normalised cross-correlation of the left patch along the
  // epipolar row band, over the disparities of targets beyond
  // stereo_min_range_m; a best score below ncc_min is no detection.
  double stereo_min_range_m = 2.0;
  double ncc_min = 0.5;
  int epipolar_slack_px = 1;  // rows searched above and below the left row
};

// Where a LiDAR node's static background comes from (lidar_preprocessor.h).
enum class LidarBackground {
  kWarmup,  // the run's first warmup_frames scans, target and all (ours, the default so far)
  kSurvey,  // scans of the static scene before the run's first frame (paper Sec. IV-A)
};
// "warmup", "survey".
const char* LidarBackgroundName(LidarBackground b);

struct LidarPreprocessConfig {
  bool raw = false;
  // "warmup" (below) or "survey": the paper's "multiple prior measurements"
  // of the static surroundings, made by sim/lidar_survey.h before the run's
  // first frame with no moving object about, long enough that
  // survey_coverage of the direction cells the scan pattern reaches within
  // survey_horizon_s are hit at least once, a cell being one voxel seen at
  // the reach of a white target head-on (max_range_m / sqrt(reference
  // reflectivity)); every voxel a survey scan returns from is static, and
  // the node reports from its first frame.
  LidarBackground background = LidarBackground::kWarmup;
  double survey_coverage = 0.99;
  double survey_horizon_s = 60.0;
  // Static background ("warmup"): voxels hit in at least occupancy_threshold of the
  // first warmup_frames scans. Nothing is reported during warm-up. The
  // default suits the default Livox-like rosette, whose non-repetitive
  // pattern hits a given 0.5 m voxel in only a few of its 0.1 s scans: one
  // hit in 20 scans makes a voxel static (a target seen during warm-up then
  // leaves its voxels as background). A spinning LiDAR hits every static
  // voxel in every scan and can use e.g. 0.5, which no passing target reaches.
  double voxel_size_m = 0.5;
  int warmup_frames = 20;
  double occupancy_threshold = 0.05;
  // A point is static if its voxel is, or (static_neighbourhood) any of the
  // 26 voxels around it is.
  bool static_neighbourhood = true;
  // DBSCAN of the dynamic points; keep the clusters_kept largest (0: keep
  // every dynamic point, unclustered). At 60 m the UAV returns 1-3 points a
  // scan, so a single point is a cluster by default.
  double cluster_eps_m = 1.0;
  int cluster_min_points = 1;
  int clusters_kept = 1;
  // Weather echoes (ours, off by default until the shipped models are
  // retrained on it; the paper's background subtraction keeps them):
  // a return whose received power fog or rain backscatter at its range could
  // reach is not the target (lidar_preprocessor.h). A fog echo's speckle
  // fade is Gamma(M, 1/M) (sensors/lidar.h; M speckle cells, >= 1), so it
  // reaches fog_echo_margin m times its mean with probability e^-m at M = 1
  // (one cell, the worst case) and below exp(-M (m - 1 - ln m)) (Chernoff)
  // for any M: 20 holds for every receiver aperture, and is far from tight
  // at the default M of thousands. A raindrop returns at most the power of
  // a drop filling the beam, and rain_echo_margin covers the range noise.
  bool weather_echo_rejection = false;
  double fog_echo_margin = 20.0;
  double rain_echo_margin = 1.2;
  // A drone or nothing (ours, off by default): with drone_gate, a cluster
  // is a candidate only if a drone could have made it
  // (lidar_preprocessor.h): its extent at most drone_max_size_m plus the
  // distance drone_max_speed_mps covers in one scan, and its point count at
  // most drone_count_margin times the returns a drone_max_size_m square
  // would give at its range with the scan's mean beam density; the largest
  // candidates are kept, and a scan with none sends nothing.
  bool drone_gate = false;
  double drone_max_size_m = 1.0;
  double drone_max_speed_mps = 20.0;
  double drone_count_margin = 4.0;
};

enum class RadarSelection {
  kLargest,     // the clusters_kept largest (paper Sec. IV-A)
  kPersistent,  // the clusters_kept best supported by the previous frames (ours)
};
// "largest", "persistent".
const char* RadarSelectionName(RadarSelection s);

struct RadarPreprocessConfig {
  bool raw = false;
  // DBSCAN on (x, y, z, velocity_weight_s * radial velocity); keep the
  // clusters_kept largest (0: keep every point). Birds form small clusters.
  double cluster_eps_m = 1.5;
  int cluster_min_points = 1;
  double velocity_weight_s = 0.0;
  int clusters_kept = 1;
  // Which clusters are kept (radar_preprocessor.h): "largest" (the paper,
  // the default until the shipped models are retrained on ours)
  // or "persistent" (ours): the clusters_kept with the most support among
  // the previous persistence_frames frames' clusters (a centroid within
  // gate_m + max_speed_mps times the frames' time apart), larger first on
  // ties; clusters supported by fewer than min_support frames are not sent.
  RadarSelection selection = RadarSelection::kLargest;
  // Rain's Doppler (ours, off by default as above; the paper: "the Doppler component can be used to
  // filter out spurious reflections"): in rain, a detection whose radial
  // velocity is that of drops falling at 2 to 9.65 m/s seen along its
  // direction (within rain_doppler_margin_mps) is dropped before clustering.
  bool rain_doppler_rejection = false;
  double rain_doppler_margin_mps = 0.5;
  int persistence_frames = 5;
  int min_support = 1;
  double gate_m = 2.0;
  double max_speed_mps = 20.0;
  // A drone or nothing (ours, issue 72; 0 = off, the default): a chosen
  // cluster whose strongest detection's SNR (dB over the CFAR's noise
  // estimate, the channel the node sends) is below min_peak_snr_db is not
  // sent. Every detection already passed the CFAR, at 10 log10(alpha) dB
  // (a few dB at the default false-alarm rate), so 0 keeps every cluster.
  // Rain clutter and noise sit just above the CFAR threshold; a drone's
  // return within its detection range well above it (NOTES.md session 32).
  double min_peak_snr_db = 0.0;
};

// What the nodes know of the weather (issue 72 item 3, issue 68 item 4):
// the LiDAR's weather-echo rejection (and its survey's) and the radar's
// rain Doppler use it; the sensors themselves always see the true weather.
enum class NodeWeatherSource {
  kTruth,    // the scenario's /weather, as from a perfect visibility meter and
             // rain gauge: an oracle, listed in a run's manifest (`oracles`)
  kAssumed,  // assumed_rain_mm_h and assumed_fog_visibility_m, whatever falls
};
const char* NodeWeatherSourceName(NodeWeatherSource s);  // "truth", "assumed"

struct NodeWeatherConfig {
  NodeWeatherSource source = NodeWeatherSource::kTruth;
  double assumed_rain_mm_h = 0.0;                  // with "assumed"; 0 = dry
  std::optional<double> assumed_fog_visibility_m;  // with "assumed"; unset = no fog
  // The weather the nodes take as the weather, given the true one.
  core::WeatherConfig Known(const core::WeatherConfig& truth) const;
};

struct PreprocessConfig {
  bool raw = false;  // every modality raw: the paper's "without preprocessing"
  // Observations a node sends per frame (issue 46: several targets). 1 (the
  // paper): the one observation its pre-processing picks. N > 1: that one
  // and up to N - 1 further ones, each its own observation with its own
  // geometric anchor and latent: the camera's next largest moving blobs
  // that pass the stereo check, the LiDAR's next largest clusters, the
  // radar's next clusters in its selection's order that pass its gate. Raw
  // pre-processing, and a LiDAR or radar keeping every point
  // (clusters_kept 0), send one.
  int max_observations = 1;
  CameraPreprocessConfig camera;
  LidarPreprocessConfig lidar;
  RadarPreprocessConfig radar;
  NodeWeatherConfig weather;

  bool CameraRaw() const { return raw || camera.raw; }
  bool LidarRaw() const { return raw || lidar.raw; }
  bool RadarRaw() const { return raw || radar.raw; }
};

// Where the nodes depart from the paper's pre-processing (Sec. IV-A): the
// switches of ours that are on, as "key=value" (a run's manifest lists
// them; with a model, its `extensions` too).
std::vector<std::string> NodeExtensions(const PreprocessConfig& p);
// The truths the nodes are handed, as "key=value" (a run's manifest lists
// them): "weather=truth" when a weather consumer is on and the nodes are
// given the true weather.
std::vector<std::string> NodeOracles(const PreprocessConfig& p);

template <class V>
void Visit(V& v, CameraPreprocessConfig& c);
template <class V>
void Visit(V& v, LidarPreprocessConfig& c);
template <class V>
void Visit(V& v, RadarPreprocessConfig& c);
template <class V>
void Visit(V& v, NodeWeatherConfig& c);
template <class V>
void Visit(V& v, PreprocessConfig& c);

}  // namespace uavsim::pipeline
