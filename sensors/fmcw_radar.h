// FMCW radar: ray-cast scatterers -> complex IF cube -> (RadarProcessor)
// point cloud (paper Sec. IV-A; issue 4).
//
// Conventions shared by synthesis and processing (tests rely on them):
// - Radar frame R: REP 103 body frame at the pose (x boresight, y left, z up).
// - Virtual array in the R y-z plane: element (ix, iy) at
//   p = (0, ix * dx, iy * dy), dx = spacing_x_wavelengths * lambda (likewise dy).
// - Direction to a target u = (cos el cos az, cos el sin az, sin el): azimuth
//   az in the x-y plane from x toward y, elevation el from that plane toward z.
// - Fast time t_s = s / fs (s = 0 .. adc_samples - 1) within a chirp; chirp c
//   starts at c * T_c with T_c = chirp_duration + idle_time.
// - A scatterer k at range R_k (at the frame's start), radial velocity v_k
//   (positive = receding) and direction u_k contributes
//     a_k exp(j [2 pi f_b t_s + 4 pi R_k / lambda + 2 pi (2 v_k / lambda) c T_c
//                + 2 pi (p . u_k) / lambda])
//   with beat frequency f_b = 2 K R_k / c, K = bandwidth / chirp_duration,
//   and |a_k|^2 the received power from the radar equation
//   P_r = P_t G^2 lambda^2 sigma / ((4 pi)^3 R^4) relative to the noise power
//   k T B F per sample (B = sample rate). The spatial phase is the paper's
//   Delta phi_x, Delta phi_y with the angles measured as above.
// - Range resolution c / (2 B_sweep); velocity resolution
//   lambda / (2 N_chirps T_c); maximum range fs c / (2 K). The range FFT's
//   bin is c fs / (2 K N_s) = c / (2 B_s), B_s = K N_s / fs the bandwidth
//   swept while the ADC samples (0.195 m at the defaults).
//
// Units of the cube: samples are in units of sqrt(k T0 fs F) (T0 = 290 K,
// F the noise figure), so thermal noise has E|n|^2 = 1 per complex sample
// (real and imaginary parts independent N(0, 1/2)) and |a_k|^2 is the
// scatterer's signal-to-noise ratio per sample; noise_power_w() gives the
// watts of one unit. Each a_k is real and positive: all phase is in the
// exponent above. The model leaves out, by the shared convention, range
// migration (10 m/s moves a target 5 cm in the 5.12 ms of chirps, a quarter
// of a range bin) and range-Doppler coupling (the beat shift 2 v / lambda,
// 0.26 range bins at 10 m/s); the Doppler progression over chirps is in it.
//
// FindScatterers (rays -> scatterers):
// - Rays over the field of view, in R: azimuth cells of
//   fov_azimuth / N_az, N_az = ceil(fov_azimuth / ray_density), elevation
//   likewise, one ray through each cell's centre, cast to max_range. A ray
//   of solid angle dOmega = d_az (sin el_hi - sin el_lo) hitting at range R
//   stands for the area A = R^2 dOmega normal to it. A hit at range R on a
//   moving object re-casts its cell and the 8 around it with n x n rays
//   each, n = min(64, ceil(R max(d_az, d_el) / object_ray_spacing_m)), A
//   shrinking accordingly; so do the cells that see a bounding sphere the
//   caller passes (FindScatterers' `refine`; R its nearest distance).
// - RCS of a hit, with theta the incidence angle from the surface normal and
//   the surface parameters of its material's radar class (config.surfaces):
//     sigma = A sigma0(theta) / cos(theta),
//     sigma0(theta) = gamma cos(theta)                                 [diffuse]
//                   + |Gamma0|^2 exp(-tan^2 theta / (2 m^2)) / (2 m^2 cos^4 theta)
//   The first term is the constant-gamma clutter model (Nathanson, Radar
//   Design Principles, 2nd ed., 1991, land clutter; Barton, Radar Equations
//   for Modern Radar, 2013); over a surface it gives sigma = gamma times
//   the area projected normal to the rays, whatever the ray density. The
//   second is the geometric-optics (Kirchhoff stationary-phase) specular lobe
//   of a rough surface of rms slope m (Ulaby, Moore & Fung, Microwave Remote
//   Sensing, Vol. II, 1982, Ch. 12): strong near normal incidence, vanishing
//   off it. Defaults (fmcw_radar_config.h):
//     ground (asphalt)  gamma -15 dB: sigma0 = -25.6 dB at 5 deg grazing,
//                       -22 to -30 dB from 10 to 2 deg (asphalt at 94 GHz
//                       and low grazing: about -20 to -30 dB, Sarabandi, Li &
//                       Nashashibi, IEEE TAP 45(11), 1997); |Gamma0|^2 0.06
//                       (eps ~ 2.7).
//     concrete          gamma -12 dB; |Gamma0|^2 0.15 from eps' = 5.24
//                       (ITU-R P.2040-1, Table 3), m = 0.15: sigma0(0) = +5 dB.
//     glass             gamma -25 dB; |Gamma0|^2 0.19 from eps' = 6.31
//                       (P.2040-1), m = 0.03: +20 dB at normal incidence, a
//                       lobe of a few degrees.
//     metal             gamma -15 dB; |Gamma0|^2 = 1 (conductor), m = 0.1.
//     vegetation        gamma -10 dB, no lobe (foliage is a volume scatterer).
//     drone             gamma -5 dB, no lobe: sigma = 0.32 x the projected
//                       area (small multirotors: 0.01-0.1 m^2 at 77 GHz).
//     bird              gamma -7 dB, no lobe: chosen for 0.001-0.01 m^2 from
//                       0.3-0.9 m wingspans seen from below or the side.
// - Velocity: RaycastScene::PointVelocity of the hit point at t_s (zero for
//   the static world).
// - Merging: hits are summed in power within cells of merge_cell_fraction
//   times the range bin, the angular resolution in direction cosines
//   (lambda / (nx dx) in u_y, lambda / (ny dy) in u_z) and, for moving
//   objects, the velocity bin; static world and each moving object merge
//   separately. The merged scatterer has the summed RCS, the
//   RCS-weighted mean range along the RCS-weighted mean direction, and the
//   RCS-weighted mean velocity: one static scatterer per occupied merge
//   cell. Summing powers drops the speckle of coherent
//   sums within a cell.
// - Multipath (config.multipath), for each moving scatterer at range R with
//   image R' in the ground plane z = 0 (reflection amplitude rho =
//   multipath_reflection, phase of the reflection not modelled): the paths
//   out direct / back via the ground and the reverse, each an extra
//   scatterer at range (R + R') / 2 arriving from the image and from the
//   direct direction, sigma rho^2 ((R + R') / 2)^4 / (R^2 R'^2), radial
//   velocity the mean of the two legs'; and the path via the ground both
//   ways, the image itself with sigma rho^4. Only when the image direction
//   lies in the field of view (every path uses it on one leg) and neither
//   leg through the bounce point is blocked.
//
// Synthesize (scatterers -> cube):
// - |a_k|^2 = P_t G^2 lambda^2 sigma / ((4 pi)^3 R^4 k T0 fs F)
//             * 10^(-2 gamma_rain R / 10^4)
//   with gamma_rain = k R_rain^alpha dB/km, ITU-R P.838-3 (eq. 1), k and
//   alpha from its regression (eqs. 2-5, core/rain_attenuation.h) at
//   carrier_ghz for config.polarization on a horizontal path (at 77 GHz,
//   horizontal: k = 1.1320, alpha = 0.7177, 11.4 dB/km at 25 mm/h).
// - Scatterers closer than 0.1 m or at or beyond max_range (whose beat would
//   alias; the IF filter of a real radar removes them) are left out. No
//   antenna pattern: G holds over the field of view, where the rays go.
// - Rain clutter (rain_mm_h > 0, config.rain_clutter): volume reflectivity
//     eta = 4.07e-4 R_rain^0.79 m^2/m^3 (R_rain in mm/h; config keys)
//   from Mie backscatter (Bohren & Huffman 1983, BHMIE series) of
//   Marshall-Palmer drops N(D) = 8000 exp(-4.1 R^-0.21 D) m^-3 mm^-1
//   (Marshall & Palmer 1948) at 77 GHz, water at 20 C (Liebe, Hufford &
//   Manabe 1991 double-Debye: eps = 8.81 - j15.9); the power law fits the
//   integral within 0.7 dB from 1 to 100 mm/h. The textbook Rayleigh law
//   eta = 7e-12 f_GHz^4 R^1.6 (Nathanson, Radar Design Principles, 1991;
//   Skolnik, Introduction to Radar Systems, 3rd ed.) agrees at 1-2 mm/h and
//   is 9 dB higher at 25 mm/h, where the larger drops are Mie scatterers.
//   The echo of ~1e6 drops per cell is a complex Gaussian field (the
//   limit of a cloud of weak random scatterers), synthesised per frame:
//   - visibility: a 1-degree ray grid over the field of view gives each
//     direction's free range; rain lies from rain_clutter_min_range_m to
//     the first surface or the last range bin's far edge;
//   - range bin b (centred on the FFT's bin b, [b - 1/2, b + 1/2) range
//     bins) holds power eta snr(R_b) (1 / r_lo - 1 / r_hi) times the
//     visible solid angle, snr(R) = P_t G^2 lambda^2 L_rain(R) /
//     ((4 pi)^3 k T0 fs F) the per-m^2 SNR at R times R^4: the integral of
//     eta R^2 dR dOmega over the bin at the radar equation's 1 / R^4;
//   - its Doppler spectrum: drops fall along -z at v_t(D) = 9.65 -
//     10.3 exp(-0.6 D) m/s (Atlas, Srivastava & Sekhon 1973, D in mm), D at
//     16 quantiles of the reflectivity-weighted spectrum D^6 N(D), seen
//     along each visible direction (radial velocity -v_t u_z), split
//     linearly between the two nearest Doppler bins;
//   - one independent field per element: complex Gaussian cells of that
//     variance taken to fast time and chirps by the 2-D inverse DFT
//     sum_{d,b} G e^{j 2 pi (d c / Nc + b s / Ns)} (the header's beat and
//     Doppler phases at the bin centres); the elements then get the spatial
//     covariance R_ab = E e^{j 2 pi (p_a - p_b) . u / lambda} over the
//     visible directions (weighted by their rain power) through its
//     Cholesky factor.
//   Its echoes are attenuated by the rain like any other (two-way).
// - Thermal noise (config.thermal_noise) as above, unit power per sample.
//
// Determinism: Synthesize draws one 64-bit key from `noise` per frame. Each
// (antenna, chirp) row's thermal noise and each element's rain field come
// from a SplitMix64 generator seeded by a key derived from it and the row or
// element (normals by Boost.Random's ziggurat); every sum has one task and a
// fixed order, and the FFTW plan is made with FFTW_ESTIMATE (no timing). So
// a seed gives the same cube bit for bit with any number of threads (TBB
// inside). FindScatterers has no
// randomness; its result does not depend on the thread count either.
// Thread safety: both use the scene's const ray queries from several
// threads; nothing may call RaycastScene::SetTime meanwhile.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/rain_attenuation.h"
#include "core/rng.h"
#include "core/weather.h"
#include "core/world_geometry.h"
#include "sensors/fmcw_radar_config.h"
#include "sensors/frames.h"
#include "sensors/radar_cube.h"
#include "sensors/raycast_scene.h"

namespace uavsim::sensors {

// A point scatterer in the world frame.
struct Scatterer {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  double rcs_m2 = 0.0;
  // What it came from: 0 the static world, k >= 1 moving object k of the
  // scene; multipath paths carry their object's id and multipath = true.
  std::int32_t object = 0;
  bool multipath = false;
};

// sigma0(theta) of `surface` (m^2 per m^2 of surface), theta the incidence
// angle from the normal (formula above); cos_incidence in [0, 1].
double BackscatterCoefficient(const RadarSurfaceConfig& surface, double cos_incidence);
// The surface parameters of a radar class.
const RadarSurfaceConfig& SurfaceOf(const RadarSurfacesConfig& surfaces, core::RadarClass c);

class FmcwRadar {
 public:
  // Throws std::invalid_argument naming the key if `config` breaks a rule of
  // its Visit (for configs built in code rather than read from JSON).
  // `scene` must outlive the radar. The radar does not move. The
  // constructor makes an FFTW plan (for the rain clutter): FFTW's planner is
  // not thread-safe, so construct radars (and RadarProcessors) on one thread
  // at a time.
  FmcwRadar(const FmcwRadarConfig& config, RaycastScene& scene);
  ~FmcwRadar();
  FmcwRadar(FmcwRadar&&) noexcept;
  FmcwRadar(const FmcwRadar&) = delete;
  FmcwRadar& operator=(const FmcwRadar&) = delete;

  // Rays over the field of view at ray_density_deg; hits become scatterers
  // with an RCS from the material's radar class and the incidence, merged
  // within a resolution cell. The caller has posed the scene at t_s; t_s
  // also times the hit points' velocities. Static world first (cell order),
  // then moving objects, then multipath. `refine` (optional): spheres that
  // enclose the moving objects at t_s (the UAVs' and birds' positions and
  // half diagonals); every cell that sees part of one is cast at the
  // refined density even if its coarse ray misses, so a small object between
  // the coarse rays (a 0.5 m UAV beyond ~60 m at 0.25 deg) is still found.
  std::vector<Scatterer> FindScatterers(double t_s,
                                        const std::vector<BoundingSphere>& refine = {}) const;

  // The IF cube of `scatterers` (radar equation amplitudes, thermal noise
  // kTBF, rain attenuation and clutter from `weather`), noise from `noise`.
  RadarCube Synthesize(const std::vector<Scatterer>& scatterers, const core::WeatherConfig& weather,
                       core::RngStream& noise) const;

  // |a|^2 of a scatterer of RCS rcs_m2 at range_m in rain_mm_h of rain:
  // its signal-to-noise ratio per sample (formula above).
  double SnrPerSample(double rcs_m2, double range_m, double rain_mm_h) const;
  // gamma_rain (dB/km) and eta (m^2/m^3) at this radar's carrier.
  double RainAttenuationDbPerKm(double rain_mm_h) const;
  double RainReflectivityPerM(double rain_mm_h) const;
  // k and alpha of gamma_rain: ITU-R P.838-3 at carrier_ghz for the
  // configured polarisation, horizontal path.
  const core::RainCoefficients& rain_coefficients() const { return rain_; }

  // The static-scene cache: on by default, the coarse grid's hits against
  // the static world are kept from the first FindScatterers, and each frame
  // re-casts through the full scene only the packets of 8 rays one of which
  // meets a moving object's bounding sphere (widened by 1 % + 1 cm). Off:
  // every ray every frame. Either way the scatterers are the same, bit for
  // bit (RaycastScene::IntersectManyStatic's guarantee; a radar outside the
  // static world's bounds or inside a moving object's sphere casts all).
  void set_static_cache(bool on) { static_cache_ = on; }
  bool static_cache() const { return static_cache_; }
  // Rays the last FindScatterers cast: coarse rays re-cast (all of them
  // without the cache) and refined rays. 0 before the first.
  std::size_t last_cast_rays() const;
  // The same switch keeps the static world's share of the IF cube: each
  // antenna's fast-time sum of the static echoes (which lead the
  // zero-velocity group) is kept with the echoes it was made of, and a
  // frame whose static echoes are the same bits (same weather, nothing new
  // hidden by a moving object) starts from it. The cube is the same, bit
  // for bit, with the switch on or off. Frames that used the kept sums so far:
  std::size_t static_sum_hits() const;

  double wavelength_m() const { return lambda_m_; }
  double slope_hz_per_s() const { return slope_hz_per_s_; }
  double chirp_period_s() const { return chirp_period_s_; }
  double max_range_m() const { return max_range_m_; }
  double range_bin_m() const { return range_bin_m_; }
  double velocity_bin_mps() const { return velocity_bin_mps_; }
  // k T0 fs F: the watts of one unit of |sample|^2.
  double noise_power_w() const { return noise_power_w_; }
  std::size_t rays_per_frame() const { return grid_.size(); }

  const FmcwRadarConfig& config() const { return config_; }
  const Eigen::Isometry3d& X_WR() const { return X_WR_; }

 private:
  struct Echo;
  // A ray of the grid (or of a refined cell) and the solid angle it stands for.
  struct RayCell {
    Eigen::Vector3f dir_w;  // unit, world frame
    double solid_angle_sr;
  };
  bool InFieldOfView(const Eigen::Vector3d& u_W) const;
  void AddMultipath(std::vector<Scatterer>& scatterers) const;
  struct GridCache;
  void CastBlocks(const std::vector<RayCell>& cells, bool static_only,
                  std::vector<RayHit>& hits) const;
  // The coarse grid's hits, from the cache where that is exact; returns the
  // rays cast.
  std::size_t CastGrid(std::vector<RayHit>& hits) const;
  // FindScatterers' steps: the nearest range at which each grid cell asked
  // to be refined (infinity: not refined), and the refined cells' rays, n x n
  // per cell in grid order, with n per cell in sub_of (0: not refined).
  std::vector<double> RefineRanges(const std::vector<RayHit>& grid_hits,
                                   const std::vector<BoundingSphere>& refine) const;
  std::vector<RayCell> RefinedRays(const std::vector<double>& refine_range_m,
                                   std::vector<int>& sub_of) const;
  // Synthesize's steps: the echoes in range; their order by radial velocity
  // and where each group of equal velocity begins in it (with the end last);
  // the separable factors of their samples (per echo: fast time and
  // elements; per group: chirps); the antennas' signals and thermal noise
  // into the cube.
  struct SampleFactors;
  struct StaticSums;
  // Where the static echoes lie in sum order: the first `count` echoes of
  // velocity group `group`, which begins at `begin` (count 0: nowhere to
  // cache), and whether the kept sums are theirs.
  struct StaticPrefix {
    std::size_t group = 0, begin = 0, count = 0;
    bool cached = false;
  };
  static StaticPrefix FindStaticPrefix(const std::vector<Echo>& echoes,
                                       const std::vector<std::size_t>& order,
                                       const std::vector<std::size_t>& group_begin);
  std::vector<Echo> EchoesOf(const std::vector<Scatterer>& scatterers, double rain_mm_h) const;
  static std::vector<std::size_t> VelocityGroups(const std::vector<Echo>& echoes,
                                                 std::vector<std::size_t>& order);
  // Echoes of a cached static prefix get no factors (their sums are kept).
  void FillEchoFactors(const std::vector<Echo>& echoes, const std::vector<std::size_t>& order,
                       const StaticPrefix& prefix, SampleFactors& f) const;
  void FillDopplerPhasors(const std::vector<Echo>& echoes, const std::vector<std::size_t>& order,
                          const std::vector<std::size_t>& group_begin, SampleFactors& f) const;
  void SumSignals(const SampleFactors& f, const std::vector<std::size_t>& group_begin,
                  const StaticPrefix& prefix, std::uint64_t frame_key, RadarCube& cube) const;
  struct RainFft;  // the FFTW plan of the rain field (FFTW stays private to sensors/)
  void AddRainClutter(double rain_mm_h, std::uint64_t frame_key, RadarCube& cube) const;

  FmcwRadarConfig config_;
  RaycastScene& scene_;
  Eigen::Isometry3d X_WR_;
  Eigen::Matrix3d R_RW_;  // world -> radar rotation
  double lambda_m_ = 0.0, slope_hz_per_s_ = 0.0, sample_rate_hz_ = 0.0, chirp_period_s_ = 0.0;
  double max_range_m_ = 0.0, range_bin_m_ = 0.0, velocity_bin_mps_ = 0.0;
  double noise_power_w_ = 0.0;
  core::RainCoefficients rain_;  // ITU-R P.838-3 at the carrier
  double snr_scale_ = 0.0;       // P_t G^2 lambda^2 / ((4 pi)^3 k T0 fs F), m^2 -> SNR at 1 m
  // The ray grid: n_az_ x n_el_ cells, azimuth fastest.
  int n_az_ = 0, n_el_ = 0;
  double d_az_rad_ = 0.0, d_el_rad_ = 0.0;
  std::vector<RayCell> grid_;
  std::unique_ptr<RainFft> rain_fft_;
  std::unique_ptr<GridCache> cache_;
  std::unique_ptr<StaticSums> static_sums_;
  bool static_cache_ = true;
};

}  // namespace uavsim::sensors
