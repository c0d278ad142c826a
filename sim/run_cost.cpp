#include "sim/run_cost.h"

#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

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
  double bytes = 0.0;
  for (const NodeConfig& n : s.nodes) {
    if (std::find(modalities.begin(), modalities.end(), n.sensor.modality()) == modalities.end())
      continue;
    const double frames = std::floor(s.duration_s * n.sensor.timing().rate_hz) + 1.0;
    bytes += frames * RecordedFrameBytes(n.sensor);
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

}  // namespace uavsim::sim
