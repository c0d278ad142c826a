// Stereo fisheye camera parameters: Mei's unified model in OpenCV omnidir's
// parameterisation (xi, fx, fy, cx, cy, k1, k2, p1, p2) plus our k3, two eyes
// separated by baseline_m along the camera's x axis (the left eye at the
// pose). The pose is the body frame of REP 103 (x forward); the optical frame
// has z along body x.
#pragma once

#include <cstdint>

#include "sensors/frame_timing.h"
#include "sim/core/pose.h"

namespace uavsim::sensors {

struct FisheyeStereoConfig {
  FrameTiming timing{30.0};  // paper: f_c = 30 Hz
  core::PoseConfig pose;
  int width_px = 640;
  int height_px = 480;
  double xi = 1.0;
  double fx_px = 230.0;
  double fy_px = 230.0;
  double cx_px = 320.0;
  double cy_px = 240.0;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  double baseline_m = 0.12;

  double RaysPerFrame() const { return 2.0 * width_px * height_px; }
  // Two 8-bit grey images.
  double RawBytesPerFrame() const { return 2.0 * width_px * height_px; }
};

template <class V>
void Visit(V& v, FisheyeStereoConfig& c);

}  // namespace uavsim::sensors
