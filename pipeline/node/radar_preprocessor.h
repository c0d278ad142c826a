// The radar sensing node's pre-processing (paper Sec. IV-A: "spurious
// targets such as birds can be eliminated by clustering the points in the
// cloud, and only retaining the largest clusters"):
//
//   clustered  DBSCAN (radar.cluster_eps_m, cluster_min_points) of each
//              frame's detections in (x, y, z, velocity_weight_s * radial
//              velocity), world metres; then clusters_kept of them are kept
//              (0 keeps every detection), chosen by radar.selection:
//     largest     the largest (the paper; equal sizes: the cluster found
//                 first in the frame's order).
//     persistent  (ours) the best supported: a cluster's support is the
//                 number of the previous persistence_frames frames with a
//                 cluster whose centroid lies within gate_m + max_speed_mps
//                 * (the frames' time apart) of its centroid. A target
//                 returns frame after frame near where it was; rain clutter,
//                 multipath and noise detections scatter. Ties: the larger,
//                 then the first found. A cluster with less than min_support
//                 is not kept (nothing is sent when none qualifies).
//   further    (max_observations N > 1, issue 46) the next N - 1 clusters
//              in the selection's order that pass its gate (persistent:
//              min_support), each an observation of its own.
//   score      (radar.min_peak_snr_db > 0, ours, issue 72) after the
//              selection, a chosen cluster whose strongest detection's SNR
//              is below min_peak_snr_db is dropped, the others keep their
//              order (with one observation a frame: the one candidate or
//              nothing, the "nothing seen" header). The selection's memory
//              (persistent) still holds every cluster.
//   rain       (radar.rain_doppler_rejection, ours; before clustering, in
//              rain only) a detection at direction u from the radar (unit,
//              world) whose radial velocity v lies in [-9.65 u_z - m,
//              -2 u_z + m] (m = rain_doppler_margin_mps) is a falling drop's
//              echo: terminal velocities of 2 to 9.65 m/s (drops of 0.5 mm
//              up, Atlas, Srivastava & Sekhon 1973) along -z. The node is
//              taken to know whether it rains (a rain gauge).
//   raw        (config.RadarRaw()) every detection.
// Either way at most PointObservation::kMaxPoints points, evenly spaced in
// the frame's order if there are more, in the frame's order. Channels 5: x,
// y, z (world, metres), radial velocity (m/s, positive receding), SNR (dB).
// t_s is the frame's t_capture_s; sensor_position_w the radar's pose
// position. Detections with non-finite values are dropped.
//
// With "persistent" the node remembers the centroids of its last
// persistence_frames frames' clusters: Process must see the frames in
// capture order, one at a time. Deterministic: the output is a pure
// function of the frames seen since construction (or Reset).
#pragma once

#include <Eigen/Core>
#include <deque>
#include <vector>

#include "core/weather.h"
#include "pipeline/node/observations.h"
#include "pipeline/node/point_clustering.h"
#include "pipeline/node/preprocess_config.h"
#include "sensors/fmcw_radar_config.h"
#include "sensors/frames.h"

namespace uavsim::pipeline {

class RadarPreprocessor {
 public:
  RadarPreprocessor(const sensors::FmcwRadarConfig& sensor, const PreprocessConfig& config,
                    const core::WeatherConfig& weather = {});

  // The observation; with `further` (cleared first) and max_observations
  // > 1, the further clusters' observations too.
  PointObservation Process(const sensors::RadarFrame& frame,
                           std::vector<PointObservation>* further = nullptr);

  // Forgets the previous frames' clusters.
  void Reset() { history_.clear(); }

 private:
  struct PastFrame {
    double t_s = 0.0;
    std::vector<Eigen::Vector3d> centroids;
  };

  // The ids of at most `count` clusters to keep, in the selection's order,
  // given the valid detections' clusters.
  std::vector<int> Choose(const sensors::RadarFrame& frame, const std::vector<std::size_t>& valid,
                          const DbscanClusters& clusters, int count);
  // The observation of the frame's points `kept` (indices, increasing).
  PointObservation ObservationOf(const sensors::RadarFrame& frame,
                                 const std::vector<std::size_t>& kept) const;

  // Whether a detection moves as falling rain seen from the radar does.
  bool IsRainEcho(const sensors::RadarPoint& p) const;

  RadarPreprocessConfig config_;
  int max_observations_;
  bool raw_;
  bool reject_rain_;
  Eigen::Vector3d sensor_position_w_;
  std::deque<PastFrame> history_;  // newest last, at most persistence_frames
};

}  // namespace uavsim::pipeline
