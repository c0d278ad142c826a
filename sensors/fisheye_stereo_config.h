// Stereo fisheye camera parameters: Mei's unified model in OpenCV omnidir's
// parameterisation (xi, fx, fy, cx, cy, k1, k2, p1, p2) plus our k3, two eyes
// separated by baseline_m along the camera's x axis (the left eye at the
// pose). The pose is the body frame of REP 103 (x forward); the optical frame
// has z along body x. Shading and sensor keys (sun, exposure, noise) feed
// FisheyeStereo's image formation; see fisheye_stereo.h for the formulas.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "core/pose.h"
#include "sensors/frame_timing.h"

namespace uavsim::sensors {

// The optical frame C of each eye in the body frame B of its pose (REP 103):
// z_C = x_B, x_C = -y_B, y_C = -z_B (the columns are C's axes written in B).
inline Eigen::Matrix3d R_BC() {
  Eigen::Matrix3d R;
  R << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  return R;
}

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

  // Sun direction in the world frame (ENU): azimuth counter-clockwise from
  // east (+x) toward north (+y), elevation above the horizon. Below the
  // horizon (elevation < 0) there is no direct sunlight.
  double sun_azimuth_deg = 210.0;
  double sun_elevation_deg = 45.0;
  // Linear gain on scene radiance before the sensor (1: a white sunlit
  // surface is near full scale at illumination 1).
  double exposure = 1.0;
  // Sensor: electrons at full scale (Poisson shot noise), Gaussian read
  // noise, and the display gamma of the 8-bit output. `sensor_noise` false
  // gives the noiseless expected image (tests).
  double full_well_e = 6000.0;
  double read_noise_e = 5.0;
  double gamma = 2.2;
  bool sensor_noise = true;

  double RaysPerFrame() const { return 2.0 * width_px * height_px; }
  // Two 8-bit grey images.
  double RawBytesPerFrame() const { return 2.0 * width_px * height_px; }
};

template <class V>
void Visit(V& v, FisheyeStereoConfig& c);

}  // namespace uavsim::sensors
