// A scanning LiDAR: one Embree ray per beam, fired over the frame period at
// each beam's own time, with reflectivity- and incidence-dependent detection,
// Beer-Lambert attenuation in fog and rain, and spurious near echoes from
// fog and rain backscatter.
//
// Scan patterns (sensor frame S per REP 103: x forward, y left, z up):
//  - spinning32: channel c at elevation el_c (config.vertical_angles_deg, or
//    evenly spaced from vertical_min_deg to vertical_max_deg; one channel:
//    their mean), azimuth az_k = k * 360 / N_az deg counter-clockwise about
//    +z from +x, N_az = ceil(360 / azimuth_resolution_deg); column k fires
//    all channels at t_k = k / (N_az * rate_hz). Beam order: column-major.
//  - livox_rosette: beam i fires at t_i = i / points_per_s, N =
//    ceil(points_per_s / rate_hz) beams a frame. Two Risley prisms turning at
//    f1 and -f2 (f1 / f2 = golden ratio) deflect the beam by
//    (fov/4) (e^{i 2 pi f1 t} + e^{-i 2 pi f2 t}), a rose curve that rotates
//    and never closes: every petal crosses the centre, and coverage of the
//    circular fov_deg grows with integration time, as on Livox Mid-40/Avia.
//    The pattern runs on absolute time, so consecutive frames differ.
//  - livox_mid360: beam i fires at t_i = i / points_per_s, N =
//    ceil(points_per_s / rate_hz) beams a frame (as the rosette). A Mid-360-
//    like scan over 360 deg x [-7, 52] deg: the azimuth turns
//    counter-clockwise about +z at f_az = 10 phi Hz (phi the golden ratio),
//    az(t) = 2 pi f_az t, and the elevation sweeps the field in a triangle
//    wave of f_el = 1000 sqrt(5) Hz, el(t) = el_min + (el_max - el_min)
//    (1 - |1 - 2 frac(f_el t)|), uniform in elevation. f_az / rate_hz and
//    f_el / f_az are irrational, so the scan never repeats and fills in over
//    time. At 200 000 points/s each 0.1 s frame spans 1.6 turns, its
//    zigzags about 1.3 deg apart in azimuth and its points about 1.3 deg
//    apart in elevation. Like the rosette, on absolute time. (Livox does not
//    publish the Mid-360's pattern; this is its field, rate and
//    non-repetitiveness, not its exact trajectory.)
//
// Detection, in normalised power units (m^-2):
//   P(R) = rho * cos(i) * xi(R) * exp(-2 alpha R) / R^2,
//   detected iff P >= P_th = reference_reflectivity / max_range_m^2,
// with rho the material's lidar_reflectivity clamped to [0, 1], i the
// incidence angle, xi the transmitter/receiver overlap (0 below
// min_range_m, linear to 1 at full_overlap_range_m; Hahner et al. 2021) and
// alpha the extinction coefficient at 905 nm (sensors/atmosphere.h, the
// optical atmosphere the camera shares at 550 nm):
//   fog:  alpha = (3.912 / V) (905 nm / 550 nm)^-q(V), Kim, McArthur & Korevaar
//         2001 (Proc. SPIE 4214), Koschmieder's 2 % contrast with Kim's q(V);
//         q = 0 below V = 500 m.
//   rain: alpha = pi N0 / Lambda^3 = 3.65e-4 R^0.63 m^-1 (R in mm/h): the
//         Marshall-Palmer drop sizes N(D) = N0 exp(-Lambda D), N0 = 8000
//         m^-3 mm^-1, Lambda = 4.1 R^-0.21 mm^-1, with the large-drop
//         extinction efficiency Q_ext = 2 (the limit LISA's Mie integral
//         reaches for raindrops, Kilic et al. 2021); 1.2 to 1.5 times the
//         free-space-optics law 1.076 R^0.67 dB/km (Carbonneau & Wisely 1998)
//         over 100 to 1 mm/h.
// A target of reference reflectivity seen head-on in clear air is therefore
// detected exactly out to max_range_m; in fog the range R* solves
// rho cos(i) exp(-2 alpha R*) / R*^2 = P_th (Beer-Lambert, two-way).
// intensity = min(1, P * saturation_range_m^2): linear in received power,
// 1 for a white target head-on at saturation_range_m (past full overlap);
// it falls as 1/R^2.
// The measured range is R + N(0, range_noise_m); each return is then lost
// with probability `dropout`.
//
// Spurious echoes (PointCloudFrame::spurious counts them; none in clear air):
//  - fog (Hahner et al. 2021, ICCV, soft-target term): backscatter
//    beta = 0.046 / V (1/(m sr), Rasshofer et al. 2011) gives one range cell
//    of fog the reflectivity rho_v = pi beta c tau / 2 (tau = pulse width),
//    so its mean echo is S(r) = rho_v xi(r) exp(-2 alpha r) / r^2. The echo
//    of many droplets is fully developed speckle, and a direct-detection
//    receiver sums the independent speckle cells its aperture intercepts,
//    M = max(1, (D theta / lambda)^2) of them (D = receiver_aperture_mm,
//    theta = beam_divergence_mrad, lambda = 905 nm; the order of magnitude
//    of Goodman's integrated speckle, Speckle Phenomena in Optics, 2007).
//    So a beam's echo is E S(r) with E ~ Gamma(M, 1/M), mean 1, variance
//    1 / M, drawn once per beam from its own stream (FogSpeckleFade). It is
//    detected with probability P(E >= P_th / max S) = Q(M, M P_th / max S)
//    (regularised upper incomplete gamma); for M of thousands a step in
//    visibility: a beam with no nearer target finds a fog echo where
//    max S >= P_th and almost never where max S is below. Its range is
//    drawn from S over the part of the profile above P_th / E, in front of
//    any target.
//  - rain (LISA, Kilic et al. 2021): drops in the beam's cone (full angle
//    beam_divergence_mrad) form a Poisson process; a drop of diameter D at r
//    returns P = 0.02 min((D / (theta r))^2, 1) xi(r) exp(-2 alpha r) / r^2
//    (water's Fresnel reflectance, n = 1.328); the detectable drops up to
//    the target are drawn exactly from the Marshall-Palmer tail.
//  The beam reports the strongest echo, or the farthest with return_mode
//  "last".
//
// Points are in the world frame at their firing time; moving objects are
// posed once per time slice (config.time_slices_per_frame slices a frame),
// so a moving UAV is smeared across the sweep as by a real scanner.
//
// Determinism: Capture draws one 64-bit key from `noise` per frame; every
// beam's randomness comes from its own stream derived from (key, beam
// index), and packets are grouped by beam index, so a seed gives the same
// cloud bit for bit with any number of threads (TBB parallel_for inside).
// Thread safety: Capture re-poses the scene (RaycastScene::SetTime) when it
// has moving objects, so no other thread may use the scene during it; it
// leaves the scene posed at the last slice's time. A scene without moving
// objects is cast in one parallel pass, with the same result.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "core/weather.h"
#include "sensors/frames.h"
#include "sensors/lidar_atmosphere.h"
#include "sensors/lidar_config.h"
#include "sensors/raycast_scene.h"

namespace uavsim::sensors {

// Extinction coefficients at 905 nm (formulas above): sensors/lidar_atmosphere.h,
// over the shared optical atmosphere of sensors/atmosphere.h.

// One beam as Capture casts it: the world-frame ray (unit direction, so t is
// in metres) and its firing time after the frame's start.
struct LidarBeam {
  Ray ray;
  float t_offset_s = 0.0f;
};

class Lidar {
 public:
  // Throws std::invalid_argument naming the field if `config` breaks a rule
  // of its Visit (for configs built in code rather than read from JSON).
  // `scene` must outlive the Lidar.
  Lidar(const LidarConfig& config, RaycastScene& scene);

  // One sweep starting at t_start_s (simulated seconds), lasting 1/rate_hz.
  PointCloudFrame Capture(double t_start_s, const core::WeatherConfig& weather,
                          core::RngStream& noise);
  // The same sweep of the static world alone, as a survey made with no
  // moving object about sees it (sim/lidar_survey.h): no moving object is
  // hit and the scene is not re-posed; the same draws from `noise`.
  PointCloudFrame CaptureStatic(double t_start_s, const core::WeatherConfig& weather,
                                core::RngStream& noise);

  // The frame's beams in firing order (for benchmarks and tests).
  std::vector<LidarBeam> Beams(double t_start_s) const;

  std::size_t beams_per_frame() const { return beam_count_; }
  double frame_period_s() const { return period_s_; }
  // P_th, in the normalised power units above.
  double detection_threshold() const { return threshold_; }
  // Rays stop here: a white target head-on is detectable out to this range.
  float max_ray_length_m() const { return ray_length_m_; }
  const Eigen::Vector3f& origin_w() const { return origin_w_; }
  const LidarConfig& config() const { return config_; }

 private:
  double BeamTime(std::size_t i) const;
  PointCloudFrame DoCapture(double t_start_s, const core::WeatherConfig& weather,
                            core::RngStream& noise, bool static_only);
  // Beams [begin, end) of one time slice, at most kBlockBeams of them, are
  // cast as one unit; the partition is fixed at construction.
  static constexpr std::size_t kBlockBeams = 64;
  struct Block {
    std::size_t begin, end;
  };
  // Rays and firing times of one block's beams.
  void BlockRays(std::size_t begin, std::size_t end, double t_start_s, Ray* rays,
                 float* times) const;

  LidarConfig config_;
  RaycastScene& scene_;
  Eigen::Matrix3f R_WS_;
  Eigen::Vector3f origin_w_;
  double period_s_ = 0.1;
  double threshold_ = 0.0;
  float ray_length_m_ = 0.0f;
  std::size_t beam_count_ = 0;
  // spinning: per-channel and per-column direction cosines
  std::size_t columns_ = 0;
  std::vector<float> cos_el_, sin_el_, cos_az_, sin_az_;
  std::vector<Block> blocks_;              // in firing order
  std::vector<std::size_t> slice_blocks_;  // slice s holds blocks [slice_blocks_[s], [s + 1])
};

}  // namespace uavsim::sensors
