#include "pipeline/node/radar_preprocessor.h"

#include <cmath>
#include <vector>

#include "pipeline/node/point_clustering.h"

namespace uavsim::pipeline {

RadarPreprocessor::RadarPreprocessor(const sensors::FmcwRadarConfig& sensor,
                                     const PreprocessConfig& config)
    : config_(config.radar), raw_(config.RadarRaw()), sensor_position_w_(sensor.pose.position_m) {}

PointObservation RadarPreprocessor::Process(const sensors::RadarFrame& frame) const {
  PointObservation obs;
  obs.t_s = frame.t_capture_s;
  obs.channels = 5;
  obs.sensor_position_w = sensor_position_w_;

  std::vector<std::size_t> valid;
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const sensors::RadarPoint& p = frame.points[i];
    if (std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.z_m) &&
        std::isfinite(p.radial_velocity_mps) && std::isfinite(p.snr_db))
      valid.push_back(i);
  }

  std::vector<std::size_t> kept;  // indices into frame.points, increasing
  if (raw_ || config_.clusters_kept == 0) {
    kept = std::move(valid);
  } else {
    const bool with_velocity = config_.velocity_weight_s > 0.0;
    const int dims = with_velocity ? 4 : 3;
    std::vector<float> features;
    features.reserve(dims * valid.size());
    for (std::size_t i : valid) {
      const sensors::RadarPoint& p = frame.points[i];
      features.insert(features.end(), {p.x_m, p.y_m, p.z_m});
      if (with_velocity)
        features.push_back(static_cast<float>(config_.velocity_weight_s * p.radial_velocity_mps));
    }
    const DbscanClusters clusters =
        Dbscan(features, dims, config_.cluster_eps_m, config_.cluster_min_points);
    std::vector<char> keep_cluster(clusters.size.size(), 0);
    for (int id : LargestClusters(clusters, config_.clusters_kept)) keep_cluster[id] = 1;
    for (std::size_t k = 0; k < valid.size(); ++k) {
      const int id = clusters.label[k];
      if (id != DbscanClusters::kNoise && keep_cluster[id]) kept.push_back(valid[k]);
    }
  }

  const std::vector<std::size_t> pick =
      EvenlySpacedIndices(kept.size(), PointObservation::kMaxPoints);
  obs.values.reserve(5 * pick.size());
  for (std::size_t k : pick) {
    const sensors::RadarPoint& p = frame.points[kept[k]];
    obs.values.insert(obs.values.end(), {p.x_m, p.y_m, p.z_m, p.radial_velocity_mps, p.snr_db});
  }
  return obs;
}

}  // namespace uavsim::pipeline
