#include "sim/run_cost.h"

#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/error.h"

namespace uavsim::sim {
namespace {

// Measured on the 2-core reference machine under the load of two other
// builds (NOTES.md, 2026-12-04; idle, runs take about 0.4x as long): the
// default run for 0.2 and 10 s (2.04e7 rays and 55 frames per simulated
// second: 1.55 and 9.3 s), the same with the LiDAR at 2000 Hz (2045 frames
// a second: 11.2 s) and with no nodes (1.0 s).
constexpr double kReferenceCores = 2.0;
constexpr double kSetupS = 1.4;            // the world's BVH, the model, the libraries
constexpr double kWallPerRayS = 3.8e-8;    // per ray cast and its pixel's or point's work
constexpr double kWallPerFrameS = 9.5e-5;  // per frame: its slices, pre-processing, message
constexpr double kWallPerSimS = 0.01;      // the event loop, uplinks, windows, scoring

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
  double rays_per_s = 0.0, frames_per_s = 0.0;
  for (const NodeConfig& n : s.nodes) {
    rays_per_s += n.sensor.RaysPerFrame() * n.sensor.timing().rate_hz;
    frames_per_s += n.sensor.timing().rate_hz;
  }
  const long cores = ::sysconf(_SC_NPROCESSORS_ONLN);
  // Nodes capture on threads of their own: more cores, proportionally less
  // wall time for the sensors' part, at best.
  const double speedup =
      std::max(1.0, static_cast<double>(cores > 0 ? cores : 1) / kReferenceCores);
  const double per_sim_s =
      (rays_per_s * kWallPerRayS + frames_per_s * kWallPerFrameS) / speedup + kWallPerSimS;
  return kSetupS + s.duration_s * per_sim_s;
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
