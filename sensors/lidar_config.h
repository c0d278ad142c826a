// LiDAR parameters. Presets: "spinning32" (32 channels, 360 deg, fixed
// vertical angles), "livox_rosette" (Livox Avia-like non-repetitive rosette,
// points_per_s over a circular field of view) and "livox_mid360" (Livox
// Mid-360-like non-repetitive scan, points_per_s over 360 deg of azimuth and
// the fixed elevations kMid360MinElevationDeg .. kMid360MaxElevationDeg).
// Ranges in metres.
//
// Detection (sensors/lidar.h has the model): a return is detected when
// rho * cos(incidence) * overlap(R) * exp(-2 alpha R) / R^2 reaches the
// threshold reference_reflectivity / max_range_m^2, i.e. a target of
// reference_reflectivity seen head-on in clear air is detected out to
// max_range_m (spec sheets quote range this way: Livox Avia 190 m at 10 %).
#pragma once

#include <cstdint>
#include <vector>

#include "core/pose.h"
#include "sensors/frame_timing.h"

namespace uavsim::sensors {

enum class LidarPreset { kSpinning32, kLivoxRosette, kLivoxMid360 };

// The Mid-360's field of view (Livox's specification: 360 deg x 59 deg, from
// -7 deg to +52 deg of elevation in its own frame, x forward, z up).
constexpr double kMid360MinElevationDeg = -7.0;
constexpr double kMid360MaxElevationDeg = 52.0;

// Which echo a beam reports when fog, rain and a target all return one.
enum class LidarReturnMode {
  kStrongest,  // the most powerful echo (the usual single-return default)
  kLast,       // the farthest echo: sees through near backscatter if the target is detectable
};

struct LidarConfig {
  FrameTiming timing{10.0};  // paper: f_l = 10 Hz
  core::PoseConfig pose;
  LidarPreset preset = LidarPreset::kSpinning32;
  // spinning
  int channels = 32;
  double vertical_min_deg = -15.0;
  double vertical_max_deg = 45.0;  // tilted up: the targets are in the air
  // Explicit elevation of each channel (e.g. a real sensor's non-uniform
  // table); empty = `channels` angles evenly spaced from vertical_min_deg to
  // vertical_max_deg, both included. When given, it has exactly `channels`
  // entries and the min/max keys are not used.
  std::vector<double> vertical_angles_deg;
  double azimuth_resolution_deg = 0.2;
  // rosette and mid360
  double points_per_s = 240000.0;
  // rosette only
  double fov_deg = 70.0;
  // both
  double max_range_m = 200.0;
  double range_noise_m = 0.02;
  double dropout = 0.0;  // probability that a return is lost
  // A Lambertian target of this reflectivity at normal incidence in clear
  // air is detected exactly out to max_range_m; sets the receiver threshold.
  double reference_reflectivity = 0.1;
  // Receiver/transmitter overlap of a biaxial sensor (Hahner et al. 2021,
  // r_1 and r_2): nothing is detected closer than min_range_m, the overlap
  // rises linearly to 1 at full_overlap_range_m. Sets how close fog and rain
  // echoes can come.
  double min_range_m = 1.0;
  double full_overlap_range_m = 10.0;  // "below 10 m in most sensors" (Hahner et al.)
  // A white (reflectivity 1) target at normal incidence at this range
  // saturates the receiver: intensity = min(1, power / power there).
  double saturation_range_m = 5.0;
  double pulse_width_ns = 5.0;        // sets the fog echo's energy (one range cell c*tau/2)
  double beam_divergence_mrad = 3.0;  // full angle; sets the rain drops a beam meets (LISA)
  // Diameter of the receiver's collecting aperture. It sets how many speckle
  // cells of a fog echo the detector sums, M = max(1, (D theta / lambda)^2)
  // with theta = beam_divergence_mrad (lidar.h), so how far a beam's fog
  // echo can stray from its mean. 25 mm is our estimate for a compact
  // Livox/Velodyne-class unit (receive lenses of one to a few centimetres
  // behind windows a few centimetres wide), not a published figure; any
  // D of 5-50 mm gives M of about 270-27 000, all near the mean.
  double receiver_aperture_mm = 25.0;
  LidarReturnMode return_mode = LidarReturnMode::kStrongest;
  // The scene is re-posed this many times per sweep (moving objects are
  // frozen within a slice of 1 / (rate_hz * time_slices_per_frame) s: 2.8 ms,
  // 5.6 cm of a 20 m/s UAV, at the defaults). Each slice costs a top-level
  // commit and a fork-join, so more slices trade speed for sharper smear.
  int time_slices_per_frame = 36;

  // Estimates in double: a validated config can still ask for more than 2^64.
  double RaysPerFrame() const;
  // The solid angle of the scan's field, steradians (spinning: the band
  // between its lowest and highest channel; rosette: the cone of fov_deg;
  // Mid-360: 360 deg x [-7, 52] deg).
  double FieldSolidAngleSr() const;
  // At most one return per ray: x, y, z, intensity and a time offset, float32.
  double RawBytesPerFrame() const { return RaysPerFrame() * 20.0; }
};

template <class V>
void Visit(V& v, LidarConfig& c);

}  // namespace uavsim::sensors
