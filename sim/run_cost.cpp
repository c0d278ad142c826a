#include "sim/run_cost.h"

#include <sys/statvfs.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/rng.h"
#include "core/world_geometry.h"
#include "pipeline/model_resolution.h"

namespace uavsim::sim {
namespace {

// The wall-time model: a run's work counted from its scenario (pixels,
// rays, IF-cube samples, encoder passes, windows) times what each unit of
// work costs this build on the project's 2-core reference machine, each
// measured by a run of scenarios/default.json's one node alone
// (docs/speed.md "Wall-time model"); the shipped scenarios check it.
constexpr double kSetupS = 1.4;              // the libraries, the world's BVH, the model
constexpr double kCameraPerPixelS = 2.9e-8;  // per eye pixel: its ray, shading, pre-processing
// per eye pixel, more, when the static-scene cache cannot serve the eye
// (execution.static_cache off, or the eye outside the static world's
// bounds: sensors/fisheye_stereo.h): every pixel is cast each frame.
constexpr double kCameraUncachedPerPixelS = 3.3e-8;
// The camera's cache needs its eye this far inside the bounds
// (kStaticBoundsMargin_m of sensors/fisheye_stereo.cpp).
constexpr double kStaticBoundsMarginM = 0.01;
constexpr double kCameraEncodeS = 2.0e-3;  // one pass of the image encoder (two 128 x 128 crops)
constexpr double kLidarPerRayS = 1.2e-7;   // per beam: its ray, pre-processing and encoder
constexpr double kRadarPerCubeSampleS = 4.0e-8;  // per IF-cube sample: synthesis, FFTs, CFAR
constexpr double kPerMethodWindowS = 8.0e-4;     // per method and alignment window, at the edge

// The static world's axis-aligned bounds (its meshes' vertices), as the
// run builds it.
Eigen::AlignedBox3d StaticBounds(const Scenario& s) {
  const core::WorldGeometry world =
      core::BuildWorldGeometry(s.world, s.base_dir, core::RngStream(s.seed, "world"));
  Eigen::AlignedBox3d box;
  for (const core::TriangleMesh& m : world.meshes)
    for (const Eigen::Vector3f& v : m.vertices_m) box.extend(v.cast<double>());
  return box;
}

// Whether the camera's static-scene cache serves its left eye (the pose's
// position; the right eye is a baseline away).
bool CameraCached(const sensors::FisheyeStereoConfig& camera, const Scenario& s,
                  const Eigen::AlignedBox3d& bounds) {
  if (!s.execution.static_cache || bounds.isEmpty()) return false;
  const Eigen::Vector3d o = camera.pose.position_m;
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(kStaticBoundsMarginM);
  return (o.array() > (bounds.min() + margin).array()).all() &&
         (o.array() < (bounds.max() - margin).array()).all();
}

// Seconds a frame of `sensor` costs its node (its capture and
// pre-processing overlap on two cores, as measured).
double FrameSeconds(const sensors::SensorConfig& sensor, const Scenario& scenario,
                    const Eigen::AlignedBox3d& bounds) {
  const pipeline::PipelineConfig& p = scenario.pipeline;
  double s = 0.0;
  switch (sensor.type) {
    case sensors::SensorType::kFisheyeStereo:
      s += (kCameraPerPixelS +
            (CameraCached(sensor.fisheye, scenario, bounds) ? 0.0 : kCameraUncachedPerPixelS)) *
           2.0 * sensor.fisheye.width_px * sensor.fisheye.height_px;
      // The image encoder runs on each observation a frame sends, at most
      // max_observations (when a learned method needs the latents).
      if (pipeline::NeedsTrainedModel(p)) s += kCameraEncodeS * p.preprocess.max_observations;
      break;
    case sensors::SensorType::kLidar:
      s += kLidarPerRayS * sensor.RaysPerFrame();
      break;
    case sensors::SensorType::kFmcwRadar: {
      const auto& r = sensor.radar;
      s += kRadarPerCubeSampleS * r.adc_samples * static_cast<double>(r.chirps_per_frame) * r.nx *
           r.ny;
      break;
    }
  }
  return s;
}

// Bytes of one recorded frame of `sensor`, at most: its files and their
// index rows.
double RecordedFrameBytes(const sensors::SensorConfig& sensor) {
  constexpr double kIndexRowBytes = 96.0, kHeaderBytes = 1024.0;
  switch (sensor.type) {
    case sensors::SensorType::kFisheyeStereo:  // two PNGs of 8-bit pixels
      return 1.01 * sensor.RawBytesPerFrame() + 2.0 * (kHeaderBytes + kIndexRowBytes);
    case sensors::SensorType::kLidar:  // a PLY of 5 floats per return, one return per ray
      return sensor.RawBytesPerFrame() + kHeaderBytes + kIndexRowBytes;
    case sensors::SensorType::kFmcwRadar: {  // the detections' PLY and the range-Doppler PNG
      const auto& r = sensor.radar;
      return 20.0 * r.processing.max_detections +
             1.01 * r.adc_samples * static_cast<double>(r.chirps_per_frame) +
             2.0 * (kHeaderBytes + kIndexRowBytes);
    }
  }
  return 0.0;
}

}  // namespace

double EstimateWallSeconds(const Scenario& s) {
  // Each node senses on a thread of its own: the nodes' work spreads over
  // the cores, but no faster than the busiest node alone.
  double total_per_s = 0.0, busiest_per_s = 0.0;
  const Eigen::AlignedBox3d bounds = StaticBounds(s);
  for (const NodeConfig& n : s.nodes) {
    const double per_s = FrameSeconds(n.sensor, s, bounds) * n.sensor.timing().rate_hz;
    total_per_s += per_s;
    busiest_per_s = std::max(busiest_per_s, per_s);
  }
  const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
  const double cores = static_cast<double>(online > 0 ? online : 1);
  // Per-core costs are the reference machine's: a machine of another core
  // count is assumed as fast per core.
  const double nodes_per_s = std::max(total_per_s / cores, busiest_per_s);
  const double edge_per_s =
      kPerMethodWindowS * static_cast<double>(s.pipeline.methods.size()) / s.pipeline.window_s;
  return kSetupS + s.duration_s * (nodes_per_s + edge_per_s);
}

double EstimateRecordBytes(const Scenario& s, const std::vector<std::string>& modalities) {
  const auto wants = [&](const std::string& m) {
    return std::find(modalities.begin(), modalities.end(), m) != modalities.end();
  };
  // recording.mcap: every frame's files base64-encoded in JSON (4/3; zstd
  // takes some of it back), a window's truth, estimates and errors, an
  // uplink message's line per frame, and the world's triangles once.
  const bool mcap = wants("mcap");
  constexpr double kBase64 = 4.0 / 3.0, kWindowBytes = 2048.0, kPerMethodBytes = 768.0,
                   kUplinkBytes = 400.0, kWorldBytes = 4e6;
  double bytes = 0.0;
  for (const NodeConfig& n : s.nodes) {
    const double frames = std::floor(s.duration_s * n.sensor.timing().rate_hz) + 1.0;
    if (wants(n.sensor.modality())) bytes += frames * RecordedFrameBytes(n.sensor);
    if (mcap) bytes += frames * (kBase64 * RecordedFrameBytes(n.sensor) + kUplinkBytes);
  }
  if (mcap) {
    const double windows = std::floor(s.duration_s / s.pipeline.window_s) + 1.0;
    bytes += kWorldBytes + windows * (kWindowBytes + kPerMethodBytes * s.pipeline.methods.size());
  }
  return bytes;
}

double FreeBytesFor(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path p = fs::absolute(path, ec);
  while (!p.empty() && !fs::exists(p, ec)) p = p.parent_path();
  struct statvfs v {};
  if (p.empty() || ::statvfs(p.c_str(), &v) != 0) return -1.0;
  return static_cast<double>(v.f_bavail) * static_cast<double>(v.f_frsize);
}

void RequireRoomToRecord(const Scenario& s, const std::vector<std::string>& record,
                         const std::string& out_dir, const std::string& command) {
  if (record.empty()) return;
  const double bytes = EstimateRecordBytes(s, record);
  const double free = FreeBytesFor(out_dir);
  if (free < 0 || bytes <= free) return;
  char text[256];
  std::snprintf(text, sizeof text,
                "%s: --record would write up to %.3g bytes; the file system of %s has %.3g free",
                command.c_str(), bytes, out_dir.c_str(), free);
  throw core::UsageError(text);
}

}  // namespace uavsim::sim
