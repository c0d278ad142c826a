// The radar sensing node's pre-processing (paper Sec. IV-A: "spurious
// targets such as birds can be eliminated by clustering the points in the
// cloud, and only retaining the largest clusters"):
//
//   clustered  DBSCAN (radar.cluster_eps_m, cluster_min_points) of each
//              frame's detections in (x, y, z, velocity_weight_s * radial
//              velocity), world metres; the clusters_kept largest kept (equal
//              sizes: the cluster found first in the frame's order); 0 keeps
//              every detection.
//   raw        (config.RadarRaw()) every detection.
// Either way at most PointObservation::kMaxPoints points, evenly spaced in
// the frame's order if there are more, in the frame's order. Channels 5: x,
// y, z (world, metres), radial velocity (m/s, positive receding), SNR (dB).
// t_s is the frame's t_capture_s; sensor_position_w the radar's pose
// position. Detections with non-finite values are dropped.
//
// Stateless between frames, hence deterministic and safe to call on a
// const object from several threads.
#pragma once

#include "pipeline/node/observations.h"
#include "pipeline/node/preprocess_config.h"
#include "sensors/fmcw_radar_config.h"
#include "sensors/frames.h"

namespace uavsim::pipeline {

class RadarPreprocessor {
 public:
  RadarPreprocessor(const sensors::FmcwRadarConfig& sensor, const PreprocessConfig& config);

  PointObservation Process(const sensors::RadarFrame& frame) const;

 private:
  RadarPreprocessConfig config_;
  bool raw_;
  Eigen::Vector3d sensor_position_w_;
};

}  // namespace uavsim::pipeline
