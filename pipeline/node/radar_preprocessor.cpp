#include "pipeline/node/radar_preprocessor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "pipeline/node/point_clustering.h"

namespace uavsim::pipeline {
namespace {

// Centroid (x, y, z) of every cluster of the valid detections.
std::vector<Eigen::Vector3d> Centroids(const sensors::RadarFrame& frame,
                                       const std::vector<std::size_t>& valid,
                                       const DbscanClusters& clusters) {
  std::vector<Eigen::Vector3d> sum(clusters.size.size(), Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < valid.size(); ++k) {
    const int id = clusters.label[k];
    if (id == DbscanClusters::kNoise) continue;
    const sensors::RadarPoint& p = frame.points[valid[k]];
    sum[static_cast<std::size_t>(id)] += Eigen::Vector3d(p.x_m, p.y_m, p.z_m);
  }
  for (std::size_t id = 0; id < sum.size(); ++id)
    sum[id] /= static_cast<double>(std::max<std::size_t>(1, clusters.size[id]));
  return sum;
}

// The strongest detection's SNR (dB) of every cluster of the valid detections.
std::vector<double> PeakSnrs(const sensors::RadarFrame& frame,
                             const std::vector<std::size_t>& valid,
                             const DbscanClusters& clusters) {
  std::vector<double> peak(clusters.size.size(), -std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k < valid.size(); ++k) {
    const int id = clusters.label[k];
    if (id == DbscanClusters::kNoise) continue;
    double& p = peak[static_cast<std::size_t>(id)];
    p = std::max(p, static_cast<double>(frame.points[valid[k]].snr_db));
  }
  return peak;
}

}  // namespace

RadarPreprocessor::RadarPreprocessor(const sensors::FmcwRadarConfig& sensor,
                                     const PreprocessConfig& config,
                                     const core::WeatherConfig& weather)
    : config_(config.radar),
      max_observations_(config.max_observations),
      raw_(config.RadarRaw()),
      reject_rain_(config.radar.rain_doppler_rejection && !config.RadarRaw() &&
                   weather.rain_mm_h > 0.0),
      sensor_position_w_(sensor.pose.position_m) {}

bool RadarPreprocessor::IsRainEcho(const sensors::RadarPoint& p) const {
  // Atlas et al. 1973: v_t(D) = 9.65 - 10.3 exp(-0.6 D); 2 m/s at D = 0.5 mm.
  constexpr double kSlowestMps = 2.0, kFastestMps = 9.65;
  const Eigen::Vector3d d = Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - sensor_position_w_;
  const double n = d.norm();
  if (!(n > 0.0)) return false;
  const double u_z = d.z() / n, m = config_.rain_doppler_margin_mps;
  const double a = -kFastestMps * u_z, b = -kSlowestMps * u_z;
  return p.radial_velocity_mps >= std::min(a, b) - m && p.radial_velocity_mps <= std::max(a, b) + m;
}

std::vector<int> RadarPreprocessor::Choose(const sensors::RadarFrame& frame,
                                           const std::vector<std::size_t>& valid,
                                           const DbscanClusters& clusters, int count) {
  if (config_.selection == RadarSelection::kLargest) return LargestClusters(clusters, count);
  const std::vector<Eigen::Vector3d> centroids = Centroids(frame, valid, clusters);
  std::vector<int> support(centroids.size(), 0);
  for (std::size_t id = 0; id < centroids.size(); ++id)
    for (const PastFrame& past : history_) {
      const double gate = config_.gate_m + config_.max_speed_mps * (frame.t_capture_s - past.t_s);
      for (const Eigen::Vector3d& c : past.centroids)
        if ((c - centroids[id]).squaredNorm() <= gate * gate) {
          ++support[id];
          break;
        }
    }
  history_.push_back({frame.t_capture_s, centroids});
  while (static_cast<int>(history_.size()) > config_.persistence_frames) history_.pop_front();

  std::vector<int> order(centroids.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    if (support[a] != support[b]) return support[a] > support[b];
    return clusters.size[a] > clusters.size[b];
  });
  std::vector<int> out;
  for (int id : order)
    if (static_cast<int>(out.size()) < count && support[id] >= config_.min_support)
      out.push_back(id);
  return out;
}

PointObservation RadarPreprocessor::ObservationOf(const sensors::RadarFrame& frame,
                                                  const std::vector<std::size_t>& kept) const {
  PointObservation obs;
  obs.t_s = frame.t_capture_s;
  obs.channels = 5;
  obs.sensor_position_w = sensor_position_w_;
  const std::vector<std::size_t> pick =
      EvenlySpacedIndices(kept.size(), PointObservation::kMaxPoints);
  obs.values.reserve(5 * pick.size());
  for (std::size_t k : pick) {
    const sensors::RadarPoint& p = frame.points[kept[k]];
    obs.values.insert(obs.values.end(), {p.x_m, p.y_m, p.z_m, p.radial_velocity_mps, p.snr_db});
  }
  return obs;
}

PointObservation RadarPreprocessor::Process(const sensors::RadarFrame& frame,
                                            std::vector<PointObservation>* further) {
  if (further) further->clear();
  std::vector<std::size_t> valid;
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const sensors::RadarPoint& p = frame.points[i];
    if (std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.z_m) &&
        std::isfinite(p.radial_velocity_mps) && std::isfinite(p.snr_db) &&
        !(reject_rain_ && IsRainEcho(p)))
      valid.push_back(i);
  }
  if (raw_ || config_.clusters_kept == 0) return ObservationOf(frame, valid);

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
  const int extra = further ? max_observations_ - 1 : 0;
  std::vector<int> chosen = Choose(frame, valid, clusters, config_.clusters_kept + extra);
  // The candidates' score (the selection's memory is left as it was).
  if (config_.min_peak_snr_db > 0.0) {
    const std::vector<double> peak = PeakSnrs(frame, valid, clusters);
    chosen.erase(
        std::remove_if(
            chosen.begin(), chosen.end(),
            [&](int id) { return peak[static_cast<std::size_t>(id)] < config_.min_peak_snr_db; }),
        chosen.end());
  }
  const ChosenPoints points =
      PointsOfClusters(clusters, chosen, static_cast<std::size_t>(config_.clusters_kept), valid);
  for (const auto& group : points.further) further->push_back(ObservationOf(frame, group));
  return ObservationOf(frame, points.kept);
}

}  // namespace uavsim::pipeline
