// LiDAR parameters. Presets: "spinning32" (32 channels, 360 deg, fixed
// vertical angles) and "livox_rosette" (Livox-like non-repetitive rosette,
// points_per_s over a circular field of view). Ranges in metres.
#pragma once

#include <cstdint>
#include <vector>

#include "sensors/frame_timing.h"
#include "sim/core/pose.h"

namespace uavsim::sensors {

enum class LidarPreset { kSpinning32, kLivoxRosette };

struct LidarConfig {
  FrameTiming timing{10.0};  // paper: f_l = 10 Hz
  core::PoseConfig pose;
  LidarPreset preset = LidarPreset::kSpinning32;
  // spinning
  int channels = 32;
  double vertical_min_deg = -15.0;
  double vertical_max_deg = 45.0;  // tilted up: the targets are in the air
  double azimuth_resolution_deg = 0.2;
  // rosette
  double points_per_s = 240000.0;
  double fov_deg = 70.0;
  // both
  double max_range_m = 200.0;
  double range_noise_m = 0.02;
  double dropout = 0.0;  // probability that a return is lost

  // Estimates in double: a validated config can still ask for more than 2^64.
  double RaysPerFrame() const;
  // At most one return per ray: x, y, z, intensity and a time offset, float32.
  double RawBytesPerFrame() const { return RaysPerFrame() * 20.0; }
};

template <class V>
void Visit(V& v, LidarConfig& c);

}  // namespace uavsim::sensors
