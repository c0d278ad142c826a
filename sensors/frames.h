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

}  // namespace uavsim::sensors
