// What sensors produce, as plain data the pipeline can read without Embree
// or the event engine. Points are in the world frame (ENU, metres).
#pragma once

#include <cstdint>
#include <vector>

namespace uavsim::sensors {

// 8-bit grey image, row-major, width * height bytes.
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
  std::uint8_t at(int u, int v) const { return pixels[static_cast<std::size_t>(v) * width + u]; }
};

struct StereoFrame {
  double t_capture_s = 0.0;  // global shutter: both eyes at this instant
  GrayImage left;
  GrayImage right;
  std::size_t RawBytes() const { return left.pixels.size() + right.pixels.size(); }
};

struct LidarPoint {
  float x_m, y_m, z_m;  // world frame
  float intensity;      // [0, 1]: received power, normalised (falls as 1/R^2; see lidar.h)
  float t_offset_s;     // time of this point after the frame's start
};

struct PointCloudFrame {
  double t_start_s = 0.0;  // start of the sweep; each point carries its own offset
  std::vector<LidarPoint> points;
  std::size_t rays_cast = 0;  // beams fired in this frame
  std::size_t spurious = 0;   // of the points, returns from fog/rain backscatter
  std::size_t RawBytes() const { return points.size() * 5 * sizeof(float); }
};

// One radar detection after CFAR and angle estimation.
struct RadarPoint {
  float x_m, y_m, z_m;        // world frame
  float radial_velocity_mps;  // positive = moving away from the radar
  float snr_db;               // of the detection cell over the CFAR noise estimate
};

// A range-Doppler power map (dB), range bins x Doppler bins, range fastest,
// zero Doppler in the middle column; for recording and inspection.
struct RangeDopplerMap {
  int range_bins = 0;
  int doppler_bins = 0;
  double range_bin_m = 0.0;
  double velocity_bin_mps = 0.0;
  std::vector<float> power_db;  // index = d * range_bins + r
};

struct RadarFrame {
  double t_capture_s = 0.0;  // start of the frame's first chirp
  std::vector<RadarPoint> points;
  RangeDopplerMap range_doppler;  // summed over antennas
  std::size_t cube_bytes = 0;     // raw: the IF cube
  std::size_t scatterers = 0;     // ray-cast scatterers that fed the cube
  std::size_t RawBytes() const { return cube_bytes; }
  std::size_t PointBytes() const { return points.size() * sizeof(RadarPoint); }
};

}  // namespace uavsim::sensors
