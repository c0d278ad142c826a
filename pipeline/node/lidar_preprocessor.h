// The LiDAR sensing node's pre-processing (paper Sec. IV-A, "the point cloud
// of the target is simply obtained by subtracting the static background
// from each LiDAR scan"):
//
//   warm-up   (lidar.background "warmup") the first lidar.warmup_frames
//             scans build a static background: a voxel (edge voxel_size_m,
//             world frame) is static if it holds a return in at least
//             occupancy_threshold of those scans. Nothing is reported
//             meanwhile (empty observations).
//   survey    (lidar.background "survey", the paper's prior measurements)
//             the background is a static map made before the first frame
//             (AddSurveyScan over sim/lidar_survey.h's scans of the static
//             scene, then SetStaticMap): a voxel is static if any survey
//             scan returned from it (weather echoes excluded as below).
//             Reported from the first frame. An object that arrives after
//             the survey (a parked car) is not in the map: its points are
//             dynamic for as long as it stays.
//   per scan  a point is dynamic unless its voxel (or, with
//             static_neighbourhood, one of the 26 around it) is static;
//             DBSCAN (cluster_eps_m, cluster_min_points) of the dynamic
//             points, the clusters_kept largest kept (0: every dynamic point).
//   further   (max_observations N > 1, issue 46) the next N - 1 largest
//             clusters, each an observation of its own (as the kept one
//             is made), largest first.
//   weather   (lidar.weather_echo_rejection, ours) before both: a return is
//             dropped when fog or rain backscatter at its range could have
//             produced its power, i.e. when P < fog_echo_margin S_fog(r) or
//             P <= rain_echo_margin P_drop(r), with P the power its
//             intensity stands for (saturated returns are kept), r its
//             distance from the sensor and S_fog, P_drop the mean fog echo
//             and the largest raindrop echo of sensors/lidar_atmosphere.h
//             for the scenario's weather (the node is taken to know the
//             visibility and rain rate, as from a visibility meter).
//   drone     (lidar.drone_gate, ours) before the clusters are chosen, a
//             cluster whose points a drone could not have returned is no
//             candidate: its bounding-box diagonal above drone_max_size_m +
//             drone_max_speed_mps / rate_hz (the drone and its smear over
//             one scan), or more points than drone_count_margin x
//             max(1, drone_max_size_m^2 / r^2 x beams / field) (a square of
//             the largest size at the cluster centroid's range r from the
//             sensor, at the scan's mean beam density: rays per frame over
//             LidarConfig::FieldSolidAngleSr). The largest candidates are
//             kept; a scan with none sends nothing. A parked car (a new
//             static object) fails both; a fog shell near the sensor fails
//             the extent.
//   raw       (config.LidarRaw()) no background, no clustering, no weather
//             rejection, from the first scan on.
// Either way at most PointObservation::kMaxPoints points, evenly spaced in
// the frame's order if there are more (EvenlySpacedIndices), in the frame's
// order. Channels 4: x, y, z (world, metres), intensity.
//
// The observation's t_s is the frame's t_start_s plus the mean t_offset_s of
// the kept points (when the target was swept), or t_start_s if none is kept.
// sensor_position_w is the LiDAR's pose position.
//
// The background is learnt once and then frozen: whatever reaches the
// occupancy threshold during warm-up is background for good. With the
// default threshold (one hit in 20 scans, for the rosette's sparse
// coverage) that includes the target's own returns during warm-up: its
// points are lost wherever it passes within a voxel of them again. Points with
// non-finite coordinates are ignored. Deterministic: the output is a pure
// function of the frames seen since construction (or Reset).
#pragma once

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/weather.h"
#include "pipeline/node/observations.h"
#include "pipeline/node/preprocess_config.h"
#include "sensors/frames.h"
#include "sensors/lidar_config.h"

namespace uavsim::pipeline {

struct DbscanClusters;

class LidarPreprocessor {
 public:
  LidarPreprocessor(const sensors::LidarConfig& sensor, const PreprocessConfig& config,
                    const core::WeatherConfig& weather = {});

  // The observation; with `further` (cleared first) and max_observations
  // > 1, the further clusters' observations too.
  PointObservation Process(const sensors::PointCloudFrame& frame,
                           std::vector<PointObservation>* further = nullptr);

  // Forgets the frame count and a background learnt in warm-up (a
  // surveyed map stays).
  void Reset();

  // Voxel keys of a static background.
  using StaticMap = std::unordered_set<std::uint64_t>;
  // Adds the voxels of a survey scan's returns to `map` (weather echoes
  // excluded when the run excludes them).
  void AddSurveyScan(const sensors::PointCloudFrame& scan, StaticMap& map) const;
  // Takes `map` as the background, as if warmed up: reported from the
  // next frame. Throws std::logic_error unless lidar.background is "survey".
  void SetStaticMap(std::shared_ptr<const StaticMap> map);

  bool warmed_up() const { return surveyed_ || frames_seen_ >= config_.warmup_frames; }
  int frames_seen() const { return frames_seen_; }
  std::size_t static_voxel_count() const { return static_voxels_ ? static_voxels_->size() : 0; }

 private:
  struct Occupancy {
    std::uint32_t frames = 0;      // warm-up scans that hit this voxel
    std::int32_t last_frame = -1;  // so a scan counts once per voxel
  };

  std::uint64_t VoxelKey(int ix, int iy, int iz) const;
  bool VoxelOf(const sensors::LidarPoint& p, int& ix, int& iy, int& iz) const;
  bool IsStatic(const sensors::LidarPoint& p) const;
  void Learn(const sensors::PointCloudFrame& frame);
  // Whether the return could be a fog or rain echo (see above).
  bool IsWeatherEcho(const sensors::LidarPoint& p) const;
  // The ids of the clusters to keep (the `k` largest, with drone_gate only
  // those a drone could have made), largest first.
  std::vector<int> ChooseClusters(const DbscanClusters& clusters, const std::vector<float>& xyz,
                                  int k) const;
  // The observation of the frame's points `kept` (indices, increasing).
  PointObservation ObservationOf(const sensors::PointCloudFrame& frame,
                                 const std::vector<std::size_t>& kept) const;

  LidarPreprocessConfig config_;
  int max_observations_;
  sensors::LidarConfig sensor_;
  core::WeatherConfig weather_;
  bool reject_weather_;
  bool raw_;
  Eigen::Vector3d sensor_position_w_;
  int frames_seen_ = 0;
  std::unordered_map<std::uint64_t, Occupancy> occupancy_;  // during warm-up only
  std::shared_ptr<const StaticMap> static_voxels_;          // null: none yet
  bool surveyed_ = false;
};

}  // namespace uavsim::pipeline
