#include "pipeline/node/lidar_preprocessor.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "pipeline/node/point_clustering.h"
#include "sensors/lidar_atmosphere.h"

namespace uavsim::pipeline {
namespace {

// 21 bits per axis: +-2^20 voxels, +-524 km at 0.5 m, far beyond any
// sensor's range; coordinates past it are clamped (and never static).
constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr std::int64_t kAxisMax = (std::int64_t{1} << kAxisBits) - 1;

std::uint64_t Pack(std::int64_t v) {
  v += kAxisOffset;
  if (v < 0) v = 0;
  if (v > kAxisMax) v = kAxisMax;
  return static_cast<std::uint64_t>(v);
}

}  // namespace

LidarPreprocessor::LidarPreprocessor(const sensors::LidarConfig& sensor,
                                     const PreprocessConfig& config,
                                     const core::WeatherConfig& weather)
    : config_(config.lidar),
      max_observations_(config.max_observations),
      sensor_(sensor),
      weather_(weather),
      reject_weather_(config.lidar.weather_echo_rejection && !config.LidarRaw() &&
                      (weather.fog_visibility_m || weather.rain_mm_h > 0.0)),
      raw_(config.LidarRaw()),
      sensor_position_w_(sensor.pose.position_m) {}

bool LidarPreprocessor::IsWeatherEcho(const sensors::LidarPoint& p) const {
  const double r = (Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - sensor_position_w_).norm();
  const double power = sensors::LidarPowerOfIntensity(sensor_, p.intensity);
  return power < config_.fog_echo_margin * sensors::FogEchoMeanPower(sensor_, weather_, r) ||
         power <= config_.rain_echo_margin * sensors::RainEchoMaxPower(sensor_, weather_, r);
}

void LidarPreprocessor::Reset() {
  frames_seen_ = 0;
  occupancy_.clear();
  if (!surveyed_) static_voxels_.reset();
}

void LidarPreprocessor::AddSurveyScan(const sensors::PointCloudFrame& scan, StaticMap& map) const {
  for (const sensors::LidarPoint& p : scan.points) {
    int ix, iy, iz;
    if (!VoxelOf(p, ix, iy, iz)) continue;
    if (reject_weather_ && IsWeatherEcho(p)) continue;
    map.insert(VoxelKey(ix, iy, iz));
  }
}

void LidarPreprocessor::SetStaticMap(std::shared_ptr<const StaticMap> map) {
  if (config_.background != LidarBackground::kSurvey)
    throw std::logic_error("LidarPreprocessor::SetStaticMap: lidar.background is not \"survey\"");
  static_voxels_ = std::move(map);
  surveyed_ = true;
  occupancy_.clear();
}

std::uint64_t LidarPreprocessor::VoxelKey(int ix, int iy, int iz) const {
  return (Pack(ix) << (2 * kAxisBits)) | (Pack(iy) << kAxisBits) | Pack(iz);
}

bool LidarPreprocessor::VoxelOf(const sensors::LidarPoint& p, int& ix, int& iy, int& iz) const {
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.z_m)) return false;
  const double inv = 1.0 / config_.voxel_size_m;
  // Clamp before the int conversion: a wild coordinate must not overflow.
  auto cell = [&](float c) {
    const double k = std::floor(c * inv);
    return static_cast<int>(std::clamp(k, -2.0 * kAxisOffset, 2.0 * kAxisOffset));
  };
  ix = cell(p.x_m);
  iy = cell(p.y_m);
  iz = cell(p.z_m);
  return true;
}

void LidarPreprocessor::Learn(const sensors::PointCloudFrame& frame) {
  for (const sensors::LidarPoint& p : frame.points) {
    int ix, iy, iz;
    if (!VoxelOf(p, ix, iy, iz)) continue;
    if (reject_weather_ && IsWeatherEcho(p)) continue;
    Occupancy& o = occupancy_[VoxelKey(ix, iy, iz)];
    if (o.last_frame == frames_seen_) continue;
    o.last_frame = frames_seen_;
    ++o.frames;
  }
}

bool LidarPreprocessor::IsStatic(const sensors::LidarPoint& p) const {
  int ix, iy, iz;
  if (!VoxelOf(p, ix, iy, iz)) return true;
  if (!static_voxels_) return false;
  const StaticMap& map = *static_voxels_;
  if (map.count(VoxelKey(ix, iy, iz))) return true;
  if (!config_.static_neighbourhood) return false;
  // Only the few non-static points get here, so the 26 look-ups stay cheap.
  // They absorb range noise that moves a surface's return across a voxel
  // face, and the sparse coverage of non-repetitive (rosette) scans.
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (map.count(VoxelKey(ix + dx, iy + dy, iz + dz))) return true;
  return false;
}

std::vector<int> LidarPreprocessor::ChooseClusters(const DbscanClusters& clusters,
                                                   const std::vector<float>& xyz, int k) const {
  if (!config_.drone_gate) return LargestClusters(clusters, k);
  const std::size_t n = clusters.size.size();
  std::vector<Eigen::AlignedBox3d> box(n);
  std::vector<Eigen::Vector3d> sum(n, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < clusters.label.size(); ++i) {
    const int c = clusters.label[i];
    if (c == DbscanClusters::kNoise) continue;
    const Eigen::Vector3d p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    box[static_cast<std::size_t>(c)].extend(p);
    sum[static_cast<std::size_t>(c)] += p;
  }
  const double max_extent_m =
      config_.drone_max_size_m + config_.drone_max_speed_mps / sensor_.timing.rate_hz;
  const double beams_per_sr = sensor_.RaysPerFrame() / sensor_.FieldSolidAngleSr();
  const double area_m2 = config_.drone_max_size_m * config_.drone_max_size_m;
  DbscanClusters plausible = clusters;
  for (std::size_t c = 0; c < n; ++c) {
    const double count = static_cast<double>(clusters.size[c]);
    if (count == 0.0) continue;
    const double r = (sum[c] / count - sensor_position_w_).norm();
    const double expected = std::max(1.0, area_m2 * beams_per_sr / std::max(r * r, 1e-6));
    if (box[c].diagonal().norm() > max_extent_m || count > config_.drone_count_margin * expected)
      plausible.size[c] = 0;
  }
  std::vector<int> chosen = LargestClusters(plausible, k);
  chosen.erase(
      std::remove_if(chosen.begin(), chosen.end(),
                     [&](int c) { return plausible.size[static_cast<std::size_t>(c)] == 0; }),
      chosen.end());
  return chosen;
}

PointObservation LidarPreprocessor::ObservationOf(const sensors::PointCloudFrame& frame,
                                                  const std::vector<std::size_t>& kept) const {
  PointObservation obs;
  obs.t_s = frame.t_start_s;
  obs.channels = 4;
  obs.sensor_position_w = sensor_position_w_;
  const std::vector<std::size_t> pick =
      EvenlySpacedIndices(kept.size(), PointObservation::kMaxPoints);
  obs.values.reserve(4 * pick.size());
  double offset_sum_s = 0.0;
  for (std::size_t k : pick) {
    const sensors::LidarPoint& p = frame.points[kept[k]];
    obs.values.insert(obs.values.end(), {p.x_m, p.y_m, p.z_m, p.intensity});
    offset_sum_s += p.t_offset_s;
  }
  if (!pick.empty()) obs.t_s += offset_sum_s / static_cast<double>(pick.size());
  return obs;
}

PointObservation LidarPreprocessor::Process(const sensors::PointCloudFrame& frame,
                                            std::vector<PointObservation>* further) {
  if (further) further->clear();
  if (!raw_ && config_.background == LidarBackground::kSurvey && !surveyed_)
    throw std::logic_error(
        "LidarPreprocessor::Process: lidar.background \"survey\" needs SetStaticMap first");
  std::vector<std::size_t> kept;  // indices into frame.points, increasing
  if (raw_) {
    kept.reserve(frame.points.size());
    for (std::size_t i = 0; i < frame.points.size(); ++i) {
      const auto& p = frame.points[i];
      if (std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.z_m)) kept.push_back(i);
    }
    ++frames_seen_;
  } else if (!warmed_up()) {
    Learn(frame);
    ++frames_seen_;
    if (warmed_up()) {
      const auto n = static_cast<double>(config_.warmup_frames);
      // The smallest whole number of scans that reaches the fraction.
      const auto min_frames = static_cast<std::uint32_t>(
          std::max(1.0, std::ceil(config_.occupancy_threshold * n - 1e-9)));
      auto map = std::make_shared<StaticMap>();
      for (const auto& [key, o] : occupancy_)
        if (o.frames >= min_frames) map->insert(key);
      static_voxels_ = std::move(map);
      occupancy_.clear();
      occupancy_.rehash(0);
    }
    return ObservationOf(frame, {});
  } else {
    std::vector<std::size_t> dynamic;
    for (std::size_t i = 0; i < frame.points.size(); ++i)
      if (!IsStatic(frame.points[i]) && !(reject_weather_ && IsWeatherEcho(frame.points[i])))
        dynamic.push_back(i);
    if (config_.clusters_kept == 0) {
      kept = std::move(dynamic);
    } else {
      std::vector<float> xyz;
      xyz.reserve(3 * dynamic.size());
      for (std::size_t i : dynamic) {
        const auto& p = frame.points[i];
        xyz.insert(xyz.end(), {p.x_m, p.y_m, p.z_m});
      }
      const DbscanClusters clusters =
          Dbscan(xyz, 3, config_.cluster_eps_m, config_.cluster_min_points);
      const int extra = further ? max_observations_ - 1 : 0;
      ChosenPoints points =
          PointsOfClusters(clusters, ChooseClusters(clusters, xyz, config_.clusters_kept + extra),
                           static_cast<std::size_t>(config_.clusters_kept), dynamic);
      kept = std::move(points.kept);
      for (const auto& group : points.further) further->push_back(ObservationOf(frame, group));
    }
    ++frames_seen_;
  }
  return ObservationOf(frame, kept);
}

}  // namespace uavsim::pipeline
