#include "sensors/fmcw_radar.h"

#include <fftw3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <boost/random/normal_distribution.hpp>
#include <cmath>
#include <complex>
#include <cstring>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <unordered_map>

#include "core/error.h"
#include "core/json_io.h"
#include "core/physical_constants.h"

namespace uavsim::sensors {
namespace {

using core::kBoltzmann_J_per_K;
using core::kPi;
using core::kSpeedOfLight_mps;
constexpr double kReferenceTemperatureK = 290.0;  // IEEE noise-figure reference T0
constexpr double kMinRangeM = 0.1;
constexpr std::size_t kBlockRays = 64;  // a multiple of kPacketRays
constexpr std::size_t kPacketRays = 8;  // RaycastScene::IntersectMany's packets
// The static cache's margins, as the camera's: moving objects' spheres
// widened by 1 % + 1 cm, the radar at least 1 cm inside the static bounds.
constexpr double kSphereMarginRel = 0.01;
constexpr double kSphereMargin_m = 0.01;
constexpr double kStaticBoundsMargin_m = 0.01;
constexpr std::size_t kRadarClasses = 7;  // core::RadarClass's enumerators
// Fast time is generated as A[q] * B[r], s = kFastBlock q + r: one complex
// multiply-add per sample, with only the short tables built per scatterer.
constexpr int kFastBlock = 32;
// Salt that separates the rain-clutter streams from the noise rows' streams.
constexpr std::uint64_t kRainStreamSalt = 0x7261696e636c7574ull;
constexpr double kRainRayStepDeg = 1.0;  // visibility rays of the rain clutter

double DbToLinear(double db) { return std::pow(10.0, db / 10.0); }

// e^{j phase} in double, phase reduced first so that the float result keeps
// its precision for phases of 1e5 rad (4 pi R / lambda at 100 m).
std::complex<double> Phasor(double phase_rad) {
  const double p = phase_rad - 2.0 * kPi * std::round(phase_rad / (2.0 * kPi));
  return {std::cos(p), std::sin(p)};
}

// acc += (cr + j ci) (b_re + j b_im) over kFastBlock samples, split re/im so
// that it vectorises.
inline void AccumulateBlock(float cr, float ci, const float* __restrict b_re,
                            const float* __restrict b_im, float* __restrict acc_re,
                            float* __restrict acc_im) {
  for (int r = 0; r < kFastBlock; ++r) {
    acc_re[r] += cr * b_re[r] - ci * b_im[r];
    acc_im[r] += cr * b_im[r] + ci * b_re[r];
  }
}

// SplitMix64 (Steele, Lea & Flood 2014) inline: the per-row noise generator,
// seeded from the row's derived key. It passes BigCrush and costs a few
// cycles, so the thermal noise of a frame (0.8 M normals) stays cheap.
class SplitMixEngine {
 public:
  using result_type = std::uint64_t;
  explicit SplitMixEngine(std::uint64_t seed) : state_(seed) {}
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }
  result_type operator()() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }

 private:
  std::uint64_t state_;
};

// A surface's backscatter model with its constants evaluated once.
struct SurfaceTerms {
  double gamma = 0.0, fresnel = 0.0, two_m2 = 1.0;
  SurfaceTerms() = default;
  explicit SurfaceTerms(const RadarSurfaceConfig& s)
      : gamma(DbToLinear(s.gamma_db)),
        fresnel(s.fresnel_reflectance),
        two_m2(2.0 * s.rms_slope * s.rms_slope) {}
  // sigma0 = gamma cos + |Gamma0|^2 exp(-tan^2 / 2m^2) / (2 m^2 cos^4)
  double Sigma0(double cos_incidence) const {
    const double c = std::clamp(cos_incidence, 0.0, 1.0);
    double sigma0 = gamma * c;
    if (fresnel > 0.0 && c > 1e-6) {
      const double c2 = c * c;
      const double exponent = (1.0 - c2) / c2 / two_m2;
      // e^-80 is 1e-35 of the lobe's peak: nothing a float cube can hold.
      if (exponent < 80.0) sigma0 += fresnel * std::exp(-exponent) / (two_m2 * c2 * c2);
    }
    return sigma0;
  }
};

// A grid cell no hit or sphere asked to refine.
constexpr double kNotRefined = std::numeric_limits<double>::infinity();

// Hits summed in power within merge cells (header: "Merging"): object,
// range, the two direction cosines and velocity (the static world has no
// velocity). Cells are hashed, so a fine merge costs memory by the hits, not
// by the cells.
class ScattererMerge {
 public:
  ScattererMerge(const FmcwRadarConfig& c, const RaycastScene& scene, const Eigen::Vector3d& origin,
                 const Eigen::Matrix3d& R_RW, double max_range_m, double range_bin_m,
                 double velocity_bin_mps, double t_s)
      : scene_(scene), origin_(origin), R_RW_(R_RW), max_range_m_(max_range_m), t_s_(t_s) {
    const double f = c.merge_cell_fraction;
    cell_r_ = f * range_bin_m;
    cell_uy_ = f / (c.nx * c.spacing_x_wavelengths);
    cell_uz_ = f / (c.ny * c.spacing_y_wavelengths);
    cell_v_ = f * velocity_bin_mps;
    for (std::size_t k = 0; k < kRadarClasses; ++k)
      terms_[k] = SurfaceTerms(SurfaceOf(c.surfaces, static_cast<core::RadarClass>(k)));
  }

  // The hit of a ray along dir_w that stands for solid_angle_sr.
  void Add(const Eigen::Vector3f& dir_w, double solid_angle_sr, const RayHit& hit) {
    if (!hit.hit() || hit.t <= 0.0f) return;
    const Eigen::Vector3d u = dir_w.cast<double>().normalized();
    const double range_m = hit.t * static_cast<double>(dir_w.norm());
    if (range_m >= max_range_m_) return;
    const double cos_i = std::abs(static_cast<double>(hit.normal_w.dot(dir_w.normalized())));
    const SurfaceTerms& surface =
        terms_[static_cast<std::size_t>(scene_.material(hit.material).radar_class)];
    const double area_m2 = range_m * range_m * solid_angle_sr;
    // sigma = A sigma0 / cos: the limit at grazing incidence is A gamma.
    const double rcs =
        cos_i > 1e-6 ? area_m2 * surface.Sigma0(cos_i) / cos_i : area_m2 * surface.gamma;
    if (!(rcs > 0.0)) return;
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    if (hit.object > 0) v = scene_.PointVelocity(hit.object, origin_ + range_m * u, t_s_);
    const Eigen::Vector3d u_R = R_RW_ * u;
    const CellKey key = {hit.object, static_cast<std::int64_t>(range_m / cell_r_),
                         static_cast<std::int64_t>(std::floor(u_R.y() / cell_uy_)),
                         static_cast<std::int64_t>(std::floor(u_R.z() / cell_uz_)),
                         static_cast<std::int64_t>(std::floor(v.dot(u) / cell_v_))};
    const auto [it, added] = cell_index_.emplace(key, sums_.size());
    if (added) {
      keys_.push_back(key);
      sums_.emplace_back();
    }
    Sum& sum = sums_[it->second];
    sum.rcs += rcs;
    sum.rcs_range += rcs * range_m;
    sum.rcs_u += rcs * u;
    sum.rcs_v += rcs * v;
  }

  // One scatterer per cell: the summed RCS at the RCS-weighted mean range
  // along the RCS-weighted mean direction, with the RCS-weighted mean
  // velocity. Cell order: the static world (object 0) first, then each
  // moving object.
  std::vector<Scatterer> Scatterers() const {
    std::vector<std::size_t> cells(sums_.size());
    std::iota(cells.begin(), cells.end(), 0);
    std::sort(cells.begin(), cells.end(),
              [&](std::size_t a, std::size_t b) { return keys_[a] < keys_[b]; });
    std::vector<Scatterer> out;
    out.reserve(cells.size());
    for (std::size_t k : cells) {
      const Sum& s = sums_[k];
      Scatterer x;
      x.position_m = origin_ + s.rcs_range / s.rcs * s.rcs_u.normalized();
      x.velocity_mps = s.rcs_v / s.rcs;
      x.rcs_m2 = s.rcs;
      x.object = static_cast<std::int32_t>(keys_[k][0]);
      out.push_back(x);
    }
    return out;
  }

 private:
  using CellKey = std::array<std::int64_t, 5>;
  struct CellHash {
    std::size_t operator()(const CellKey& k) const {
      std::uint64_t h = 0;
      for (std::int64_t x : k) h = core::Mix64(h ^ static_cast<std::uint64_t>(x));
      return static_cast<std::size_t>(h);
    }
  };
  struct Sum {
    double rcs = 0.0, rcs_range = 0.0;
    Eigen::Vector3d rcs_u = Eigen::Vector3d::Zero();
    Eigen::Vector3d rcs_v = Eigen::Vector3d::Zero();
  };

  const RaycastScene& scene_;
  Eigen::Vector3d origin_;
  Eigen::Matrix3d R_RW_;
  double max_range_m_, t_s_;
  double cell_r_ = 0.0, cell_uy_ = 0.0, cell_uz_ = 0.0, cell_v_ = 0.0;
  std::array<SurfaceTerms, kRadarClasses> terms_;
  std::unordered_map<CellKey, std::size_t, CellHash> cell_index_;
  std::vector<CellKey> keys_;
  std::vector<Sum> sums_;
};

// Reflectivity-weighted drop diameters at which the rain's fall speeds are taken.
constexpr int kDropNodes = 16;

// The rain clutter's visibility rays: a kRainRayStepDeg grid over the field
// of view, each with its direction in R, its solid angle and its hit.
struct RainView {
  std::vector<Ray> rays;
  std::vector<double> omega;
  std::vector<Eigen::Vector3d> dirs_R;
  std::vector<RayHit> hits;
};

RainView CastRainView(const FmcwRadarConfig& c, const RaycastScene& scene,
                      const Eigen::Isometry3d& X_WR, double max_range_m) {
  const Eigen::Vector3d o = X_WR.translation();
  const Eigen::Matrix3d R_WR = X_WR.linear();
  const int n_az = std::max(1, static_cast<int>(std::ceil(c.fov_azimuth_deg / kRainRayStepDeg)));
  const int n_el = std::max(1, static_cast<int>(std::ceil(c.fov_elevation_deg / kRainRayStepDeg)));
  const double d_az = c.fov_azimuth_deg * kPi / 180.0 / n_az;
  const double d_el = c.fov_elevation_deg * kPi / 180.0 / n_el;
  const std::size_t n_rays = static_cast<std::size_t>(n_az) * n_el;
  RainView view;
  std::vector<Ray>& rays = view.rays;
  std::vector<double>& omega = view.omega;
  std::vector<Eigen::Vector3d>& dirs_R = view.dirs_R;
  std::vector<RayHit>& hits = view.hits;
  rays.resize(n_rays);
  omega.resize(n_rays);
  dirs_R.resize(n_rays);
  for (int j = 0; j < n_el; ++j) {
    const double el_lo = -0.5 * c.fov_elevation_deg * kPi / 180.0 + j * d_el;
    const double el = el_lo + 0.5 * d_el;
    for (int i = 0; i < n_az; ++i) {
      const double az = -0.5 * c.fov_azimuth_deg * kPi / 180.0 + (i + 0.5) * d_az;
      const std::size_t k = static_cast<std::size_t>(j) * n_az + i;
      dirs_R[k] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
      // dOmega = d_az (sin el_hi - sin el_lo)
      omega[k] = d_az * (std::sin(el_lo + d_el) - std::sin(el_lo));
      rays[k] = {o.cast<float>(), (R_WR * dirs_R[k]).cast<float>(), 1e-3f,
                 static_cast<float>(max_range_m)};
    }
  }
  hits.resize(n_rays);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_rays, kBlockRays),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      scene.IntersectMany(&rays[r.begin()], &hits[r.begin()], r.size());
                    });
  return view;
}

// Fall speeds: 16 equal-weight quantiles of the reflectivity-weighted drop
// diameter, D^6 exp(-Lambda D), i.e. D ~ Gamma(7, 1 / Lambda).
std::array<double, kDropNodes> RainFallSpeeds(double rain_mm_h) {
  const double lambda_per_mm = 4.1 * std::pow(rain_mm_h, -0.21);  // Marshall-Palmer
  std::array<double, kDropNodes> fall_mps{};
  for (int q = 0; q < kDropNodes; ++q) {
    const double p = (q + 0.5) / kDropNodes;
    auto gamma7_cdf = [](double x) {
      double term = 1.0, sum = 1.0;
      for (int k = 1; k < 7; ++k) sum += (term *= x / k);
      return 1.0 - std::exp(-x) * sum;
    };
    double lo = 0.0, hi = 60.0;
    for (int it = 0; it < 60; ++it) (gamma7_cdf(0.5 * (lo + hi)) < p ? lo : hi) = 0.5 * (lo + hi);
    const double d_mm = 0.5 * (lo + hi) / lambda_per_mm;
    fall_mps[q] = std::max(0.0, 9.65 - 10.3 * std::exp(-0.6 * d_mm));  // Atlas et al. 1973
  }
  return fall_mps;
}

// Solid angle of rain visible at each range bin from first_bin on, per
// Doppler bin (index b * nc + d), and each direction's rain power weight
// (for the spatial covariance) into power_weight.
std::vector<double> RainSpectrum(const FmcwRadar& radar, const RainView& view,
                                 const std::array<double, kDropNodes>& fall_mps, int first_bin,
                                 std::vector<double>& power_weight) {
  const FmcwRadarConfig& c = radar.config();
  const int ns = c.adc_samples, nc = c.chirps_per_frame;
  const double range_bin_m = radar.range_bin_m();
  const std::size_t n_rays = view.rays.size();
  // Solid angle of rain per (last visible bin, Doppler bin); a suffix sum
  // over bins then gives the solid angle visible at each bin, per Doppler.
  std::vector<double> spectrum(static_cast<std::size_t>(ns) * nc, 0.0);
  power_weight.assign(n_rays, 0.0);
  const double r_first = std::max(c.rain_clutter_min_range_m, (first_bin - 0.5) * range_bin_m);
  for (std::size_t k = 0; k < n_rays; ++k) {
    const double free_m = view.hits[k].hit() ? view.hits[k].t : radar.max_range_m();
    const int last = std::min(ns - 1, static_cast<int>(std::ceil(free_m / range_bin_m)) - 1);
    if (last < first_bin) continue;
    power_weight[k] = view.omega[k] * (1.0 / r_first - 1.0 / ((last + 0.5) * range_bin_m));
    const double up = view.rays[k].direction.cast<double>().z();
    for (int q = 0; q < kDropNodes; ++q) {
      // Radial velocity of a drop falling along -z, in Doppler bins.
      const double x = -fall_mps[q] * up / radar.velocity_bin_mps();
      const double lo = std::floor(x), frac = x - lo;
      const int d0 = ((static_cast<int>(lo) % nc) + nc) % nc, d1 = (d0 + 1) % nc;
      const double w = view.omega[k] / kDropNodes;
      spectrum[static_cast<std::size_t>(last) * nc + d0] += w * (1.0 - frac);
      spectrum[static_cast<std::size_t>(last) * nc + d1] += w * frac;
    }
  }
  for (int b = ns - 2; b >= first_bin; --b)
    for (int d = 0; d < nc; ++d)
      spectrum[static_cast<std::size_t>(b) * nc + d] +=
          spectrum[static_cast<std::size_t>(b + 1) * nc + d];
  return spectrum;
}

// The standard deviation of Re and Im of each rain cell (index d * ns + b).
// Cell variance: eta (visible solid angle) integral of R^2 dR over the bin
// at SNR per m^2 snr_scale L(R) / R^4.
std::vector<float> RainCellSigma(const FmcwRadar& radar, double rain_mm_h, double eta,
                                 int first_bin, const std::vector<double>& spectrum) {
  const FmcwRadarConfig& c = radar.config();
  const int ns = c.adc_samples, nc = c.chirps_per_frame;
  const double range_bin_m = radar.range_bin_m();
  std::vector<float> sigma(static_cast<std::size_t>(ns) * nc, 0.0f);
  for (int b = first_bin; b < ns; ++b) {
    const double r_lo = std::max(c.rain_clutter_min_range_m, (b - 0.5) * range_bin_m);
    const double r_hi = (b + 0.5) * range_bin_m;
    if (r_hi <= r_lo) continue;
    const double per_sr = eta * radar.SnrPerSample(1.0, 0.5 * (r_lo + r_hi), rain_mm_h) *
                          std::pow(0.5 * (r_lo + r_hi), 4) * (1.0 / r_lo - 1.0 / r_hi);
    for (int d = 0; d < nc; ++d)
      sigma[static_cast<std::size_t>(d) * ns + b] = static_cast<float>(
          std::sqrt(0.5 * per_sr * spectrum[static_cast<std::size_t>(b) * nc + d]));
  }
  return sigma;
}

// Spatial covariance of the elements under rain from the visible
// directions, R_ab = sum w e^{j 2 pi (p_a - p_b) . u / lambda} / sum w, and
// its Cholesky factor, which imposes it on independent fields; none when no
// direction sees rain.
std::optional<Eigen::MatrixXcd> RainSpatialMix(const FmcwRadarConfig& c, const RainView& view,
                                               const std::vector<double>& power_weight) {
  const int antennas = c.nx * c.ny;
  Eigen::MatrixXcd cov = Eigen::MatrixXcd::Zero(antennas, antennas);
  double weight_sum = 0.0;
  Eigen::VectorXcd steer(antennas);
  for (std::size_t k = 0; k < view.rays.size(); ++k) {
    if (power_weight[k] <= 0.0) continue;
    const std::complex<double> ex =
        Phasor(2.0 * kPi * c.spacing_x_wavelengths * view.dirs_R[k].y());
    const std::complex<double> ey =
        Phasor(2.0 * kPi * c.spacing_y_wavelengths * view.dirs_R[k].z());
    std::complex<double> py = 1.0;
    for (int iy = 0; iy < c.ny; ++iy, py *= ey) {
      std::complex<double> pxy = py;
      for (int ix = 0; ix < c.nx; ++ix, pxy *= ex) steer(iy * c.nx + ix) = pxy;
    }
    cov.noalias() += power_weight[k] * steer * steer.adjoint();
    weight_sum += power_weight[k];
  }
  if (weight_sum <= 0.0) return std::nullopt;
  cov /= weight_sum;
  cov.diagonal().array() += 1e-9;  // keeps the factorisation defined when directions repeat
  return Eigen::MatrixXcd(cov.llt().matrixL());
}

}  // namespace

double BackscatterCoefficient(const RadarSurfaceConfig& surface, double cos_incidence) {
  return SurfaceTerms(surface).Sigma0(cos_incidence);
}

const RadarSurfaceConfig& SurfaceOf(const RadarSurfacesConfig& s, core::RadarClass c) {
  switch (c) {
    case core::RadarClass::kGround:
      return s.ground;
    case core::RadarClass::kConcrete:
      return s.concrete;
    case core::RadarClass::kGlass:
      return s.glass;
    case core::RadarClass::kMetal:
      return s.metal;
    case core::RadarClass::kVegetation:
      return s.vegetation;
    case core::RadarClass::kDrone:
      return s.drone;
    case core::RadarClass::kBird:
      return s.bird;
  }
  return s.concrete;
}

struct FmcwRadar::RainFft {
  fftwf_plan plan = nullptr;
  RainFft(int chirps, int samples) {
    // FFTW_ESTIMATE: the plan, and so every bit of the result, does not
    // depend on timing measurements; FFTW_UNALIGNED: any std::vector will do.
    std::vector<std::complex<float>> buffer(static_cast<std::size_t>(chirps) * samples);
    auto* p = reinterpret_cast<fftwf_complex*>(buffer.data());
    plan = fftwf_plan_dft_2d(chirps, samples, p, p, FFTW_BACKWARD, FFTW_ESTIMATE | FFTW_UNALIGNED);
    if (!plan) throw std::runtime_error("FmcwRadar: FFTW could not plan the rain field");
  }
  ~RainFft() { fftwf_destroy_plan(plan); }
  RainFft(const RainFft&) = delete;
  RainFft& operator=(const RainFft&) = delete;
  // In place: g[c][s] = sum_{d,b} g[d][b] e^{+j 2 pi (d c / Nc + b s / Ns)}.
  void Inverse(std::complex<float>* g) const {
    auto* p = reinterpret_cast<fftwf_complex*>(g);
    fftwf_execute_dft(plan, p, p);
  }
};

// One scatterer as the synthesis needs it, in the radar frame.
struct FmcwRadar::Echo {
  double range_m = 0.0;
  double radial_velocity_mps = 0.0;
  Eigen::Vector3d u_R = Eigen::Vector3d::UnitX();
  double snr = 0.0;           // |a|^2
  bool static_world = false;  // from the static world (not a moving object or its multipath)

  // The same bits (what the sums are made of).
  bool SameAs(const Echo& o) const {
    return std::memcmp(&range_m, &o.range_m, sizeof range_m) == 0 &&
           std::memcmp(u_R.data(), o.u_R.data(), 3 * sizeof(double)) == 0 &&
           std::memcmp(&snr, &o.snr, sizeof snr) == 0 && static_world == o.static_world;
  }
};

// The static world's share of the IF cube (issue 44): the static echoes are
// the first of their velocity group (zero; VelocityGroups' sort is stable
// and the static world comes first among the scatterers), so each
// antenna's fast-time sum of the group begins with their sum, made in the
// same order whatever follows. Kept from the last frame with the echoes it
// was made of; a frame whose static echoes are the same bits (the weather
// and what moving objects hide unchanged) starts from it: the same bits as
// summing them again.
struct FmcwRadar::StaticSums {
  std::mutex mutex;
  std::vector<Echo> echoes;       // in sum order
  std::vector<float> s_re, s_im;  // [antenna * padded + sample]
  std::size_t hits = 0;           // frames that used it
};

// The coarse grid's hits against the static world alone, made at the first
// FindScatterers with the cache on (once; a radar captures one frame at a
// time, but call_once keeps a second thread from reading it half made).
struct FmcwRadar::GridCache {
  std::once_flag built;
  bool usable = false;  // the radar stands inside the static world's bounds
  std::vector<RayHit> static_hits;
  std::atomic<std::size_t> last_cast_rays{0};
};

// The grid's rays in blocks of kBlockRays, in parallel; each block goes
// through the scene's packets of 8 as one IntersectMany call.
void FmcwRadar::CastBlocks(const std::vector<RayCell>& cells, bool static_only,
                           std::vector<RayHit>& hits) const {
  const Eigen::Vector3f origin_f = X_WR_.translation().cast<float>();
  const float t_max = static_cast<float>(max_range_m_);
  hits.assign(cells.size(), RayHit{});
  const std::size_t blocks = (cells.size() + kBlockRays - 1) / kBlockRays;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::array<Ray, kBlockRays> rays;
                      for (std::size_t b = r.begin(); b != r.end(); ++b) {
                        const std::size_t begin = b * kBlockRays;
                        const std::size_t n = std::min(kBlockRays, cells.size() - begin);
                        for (std::size_t i = 0; i < n; ++i)
                          rays[i] = {origin_f, cells[begin + i].dir_w, 1e-3f, t_max};
                        if (static_only)
                          scene_.IntersectManyStatic(rays.data(), hits.data() + begin, n);
                        else
                          scene_.IntersectMany(rays.data(), hits.data() + begin, n);
                      }
                    });
}

std::size_t FmcwRadar::CastGrid(std::vector<RayHit>& hits) const {
  GridCache& cache = *cache_;
  std::size_t built = 0;
  if (static_cache_) {
    std::call_once(cache.built, [&] {
      const Eigen::AlignedBox3d bounds = scene_.static_bounds();
      const Eigen::Vector3d o = X_WR_.translation().cast<float>().cast<double>();
      const Eigen::Vector3d margin = Eigen::Vector3d::Constant(kStaticBoundsMargin_m);
      cache.usable = !bounds.isEmpty() && (o.array() > (bounds.min() + margin).array()).all() &&
                     (o.array() < (bounds.max() - margin).array()).all();
      if (!cache.usable) return;
      CastBlocks(grid_, /*static_only=*/true, cache.static_hits);
      built = grid_.size();
    });
  }
  if (!static_cache_ || !cache.usable) {
    CastBlocks(grid_, /*static_only=*/false, hits);
    return grid_.size();
  }
  // A ray's hit can differ from the static world's only if the ray meets a
  // moving object's sphere (widened as the camera's cache widens it); its
  // packet of 8 is then cast whole through the full scene, as the full cast
  // casts it (Embree's traversal depends on the packet's active rays).
  struct Cone {
    Eigen::Vector3d axis;
    double cos_half;
  };
  std::vector<Cone> cones;
  const Eigen::Vector3d o = X_WR_.translation().cast<float>().cast<double>();
  for (const BoundingSphere& sphere : scene_.moving_object_bounds()) {
    const double radius_m = sphere.radius_m * (1.0 + kSphereMarginRel) + kSphereMargin_m;
    const Eigen::Vector3d to_center = sphere.center_m - o;
    const double distance_m = to_center.norm();
    if (!(distance_m > radius_m)) {  // the radar is inside (or the pose is not finite)
      CastBlocks(grid_, /*static_only=*/false, hits);
      return built + grid_.size();
    }
    if (distance_m - radius_m > max_range_m_) continue;  // beyond every ray's end
    const double sin_half = radius_m / distance_m;
    cones.push_back({to_center / distance_m, std::sqrt(1.0 - sin_half * sin_half)});
  }
  hits = cache.static_hits;
  if (cones.empty()) return built;
  const Eigen::Vector3f origin_f = X_WR_.translation().cast<float>();
  const float t_max = static_cast<float>(max_range_m_);
  std::size_t cast = 0;
  std::array<Ray, kPacketRays> rays;
  for (std::size_t first = 0; first < grid_.size(); first += kPacketRays) {
    const std::size_t n = std::min(kPacketRays, grid_.size() - first);
    bool meets = false;
    for (std::size_t i = first; i < first + n && !meets; ++i) {
      const Eigen::Vector3d d = grid_[i].dir_w.cast<double>().normalized();
      for (const Cone& cone : cones)
        if (d.dot(cone.axis) >= cone.cos_half) {
          meets = true;
          break;
        }
    }
    if (!meets) continue;
    for (std::size_t i = 0; i < n; ++i) rays[i] = {origin_f, grid_[first + i].dir_w, 1e-3f, t_max};
    scene_.IntersectMany(rays.data(), hits.data() + first, n);
    cast += n;
  }
  return built + cast;
}

std::size_t FmcwRadar::last_cast_rays() const { return cache_->last_cast_rays; }

FmcwRadar::FmcwRadar(const FmcwRadarConfig& config, RaycastScene& scene)
    : config_(config), scene_(scene) {
  // The JSON rules are the one statement of what is valid: run them on a
  // round trip rather than repeating them here.
  try {
    FmcwRadarConfig checked;
    core::FromJson(core::ToJson(config), "FmcwRadarConfig", "", checked);
  } catch (const core::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
  const FmcwRadarConfig& c = config_;
  lambda_m_ = kSpeedOfLight_mps / (c.carrier_ghz * 1e9);
  rain_ = core::RainCoefficientsFor(c.carrier_ghz, c.polarization);
  slope_hz_per_s_ = c.bandwidth_mhz * 1e6 / (c.chirp_duration_us * 1e-6);
  sample_rate_hz_ = c.sample_rate_msps * 1e6;
  chirp_period_s_ = (c.chirp_duration_us + c.idle_time_us) * 1e-6;
  max_range_m_ = sample_rate_hz_ * kSpeedOfLight_mps / (2.0 * slope_hz_per_s_);
  range_bin_m_ = max_range_m_ / c.adc_samples;
  velocity_bin_mps_ = lambda_m_ / (2.0 * c.chirps_per_frame * chirp_period_s_);
  noise_power_w_ =
      kBoltzmann_J_per_K * kReferenceTemperatureK * sample_rate_hz_ * DbToLinear(c.noise_figure_db);
  // Radar equation over kTBF: P_t G^2 lambda^2 / ((4 pi)^3 k T0 fs F)
  const double gain = DbToLinear(c.antenna_gain_dbi);
  snr_scale_ = DbToLinear(c.tx_power_dbm - 30.0) * gain * gain * lambda_m_ * lambda_m_ /
               (std::pow(4.0 * kPi, 3) * noise_power_w_);

  X_WR_ = c.pose.ToIsometry();
  R_RW_ = X_WR_.linear().transpose();
  n_az_ = static_cast<int>(std::ceil(c.fov_azimuth_deg / c.ray_density_deg));
  n_el_ = static_cast<int>(std::ceil(c.fov_elevation_deg / c.ray_density_deg));
  d_az_rad_ = c.fov_azimuth_deg * kPi / 180.0 / n_az_;
  d_el_rad_ = c.fov_elevation_deg * kPi / 180.0 / n_el_;
  const double az0 = -0.5 * c.fov_azimuth_deg * kPi / 180.0;
  const double el0 = -0.5 * c.fov_elevation_deg * kPi / 180.0;
  const Eigen::Matrix3d R_WR = X_WR_.linear();
  grid_.resize(static_cast<std::size_t>(n_az_) * n_el_);
  for (int j = 0; j < n_el_; ++j) {
    const double el = el0 + (j + 0.5) * d_el_rad_;
    const double omega =
        d_az_rad_ * (std::sin(el0 + (j + 1) * d_el_rad_) - std::sin(el0 + j * d_el_rad_));
    for (int i = 0; i < n_az_; ++i) {
      const double az = az0 + (i + 0.5) * d_az_rad_;
      const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      grid_[static_cast<std::size_t>(j) * n_az_ + i] = {(R_WR * u).cast<float>(), omega};
    }
  }
  rain_fft_ = std::make_unique<RainFft>(c.chirps_per_frame, c.adc_samples);
  cache_ = std::make_unique<GridCache>();
  static_sums_ = std::make_unique<StaticSums>();
}

FmcwRadar::~FmcwRadar() = default;
FmcwRadar::FmcwRadar(FmcwRadar&&) noexcept = default;

double FmcwRadar::RainAttenuationDbPerKm(double rain_mm_h) const {
  if (rain_mm_h <= 0.0) return 0.0;
  // ITU-R P.838-3 eq. (1)
  return rain_.k * std::pow(rain_mm_h, rain_.alpha);
}

double FmcwRadar::RainReflectivityPerM(double rain_mm_h) const {
  if (rain_mm_h <= 0.0) return 0.0;
  return config_.rain_clutter_eta_coefficient *
         std::pow(rain_mm_h, config_.rain_clutter_eta_exponent);
}

double FmcwRadar::SnrPerSample(double rcs_m2, double range_m, double rain_mm_h) const {
  const double r2 = range_m * range_m;
  const double loss_db = 2.0 * RainAttenuationDbPerKm(rain_mm_h) * range_m / 1000.0;
  return snr_scale_ * rcs_m2 / (r2 * r2) * DbToLinear(-loss_db);
}

bool FmcwRadar::InFieldOfView(const Eigen::Vector3d& u_W) const {
  const Eigen::Vector3d u = R_RW_ * u_W;
  const double az_deg = std::atan2(u.y(), u.x()) * 180.0 / kPi;
  const double el_deg = std::asin(std::clamp(u.z(), -1.0, 1.0)) * 180.0 / kPi;
  return std::abs(az_deg) <= 0.5 * config_.fov_azimuth_deg &&
         std::abs(el_deg) <= 0.5 * config_.fov_elevation_deg;
}

std::vector<Scatterer> FmcwRadar::FindScatterers(double t_s,
                                                 const std::vector<BoundingSphere>& refine) const {
  const std::vector<RayCell>& grid = grid_;
  std::vector<RayHit> grid_hits;
  const std::size_t cast_rays = CastGrid(grid_hits);

  // Cells near a moving object, or that see a sphere the caller passed, are
  // re-cast finer.
  const std::vector<double> refine_range_m = RefineRanges(grid_hits, refine);
  std::vector<int> sub_of;  // rays per side of a refined cell
  const std::vector<RayCell> fine = RefinedRays(refine_range_m, sub_of);
  std::vector<RayHit> fine_hits;
  if (!fine.empty()) CastBlocks(fine, /*static_only=*/false, fine_hits);
  cache_->last_cast_rays = cast_rays + fine.size();

  ScattererMerge merge(config_, scene_, X_WR_.translation(), R_RW_, max_range_m_, range_bin_m_,
                       velocity_bin_mps_, t_s);
  std::size_t next_fine = 0;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    if (sub_of[k] == 0) {
      merge.Add(grid[k].dir_w, grid[k].solid_angle_sr, grid_hits[k]);
      continue;
    }
    for (int m = 0; m < sub_of[k] * sub_of[k]; ++m, ++next_fine)
      merge.Add(fine[next_fine].dir_w, fine[next_fine].solid_angle_sr, fine_hits[next_fine]);
  }
  std::vector<Scatterer> out = merge.Scatterers();
  if (config_.multipath) AddMultipath(out);
  return out;
}

std::vector<double> FmcwRadar::RefineRanges(const std::vector<RayHit>& grid_hits,
                                            const std::vector<BoundingSphere>& refine) const {
  const FmcwRadarConfig& c = config_;
  const Eigen::Vector3d origin = X_WR_.translation();
  const double az0 = -0.5 * c.fov_azimuth_deg * kPi / 180.0;
  const double el0 = -0.5 * c.fov_elevation_deg * kPi / 180.0;
  std::vector<double> refine_range_m(grid_.size(), kNotRefined);
  auto mark = [&](int j, int i, double range_m) {
    double& r = refine_range_m[static_cast<std::size_t>(j) * n_az_ + i];
    r = std::min(r, range_m);
  };
  for (int j = 0; j < n_el_; ++j)
    for (int i = 0; i < n_az_; ++i) {
      const RayHit& h = grid_hits[static_cast<std::size_t>(j) * n_az_ + i];
      if (h.object < 1) continue;
      for (int jj = std::max(0, j - 1); jj <= std::min(n_el_ - 1, j + 1); ++jj)
        for (int ii = std::max(0, i - 1); ii <= std::min(n_az_ - 1, i + 1); ++ii) mark(jj, ii, h.t);
    }
  for (const BoundingSphere& b : refine) {
    const Eigen::Vector3d d = R_RW_ * (b.center_m - origin);
    const double dist = d.norm();
    if (!(dist > b.radius_m) || !(b.radius_m > 0.0)) continue;
    // The sphere's angular radius, widened by a cell so that every cell
    // whose footprint (not only its centre ray) touches it is caught.
    const double alpha = std::asin(b.radius_m / dist);
    const double el = std::asin(d.z() / dist), az = std::atan2(d.y(), d.x());
    const double half_el = alpha + d_el_rad_;
    const double cos_el = std::cos(std::min(0.5 * kPi, std::abs(el) + half_el));
    const double half_az =
        cos_el > std::sin(alpha) ? std::asin(std::sin(alpha) / cos_el) + d_az_rad_ : kPi;
    auto index = [](double x, double lo, double step, int n) {
      return std::clamp(static_cast<int>(std::floor((x - lo) / step)), 0, n - 1);
    };
    for (int j = index(el - half_el, el0, d_el_rad_, n_el_);
         j <= index(el + half_el, el0, d_el_rad_, n_el_); ++j)
      for (int i = index(az - half_az, az0, d_az_rad_, n_az_);
           i <= index(az + half_az, az0, d_az_rad_, n_az_); ++i)
        mark(j, i, dist - b.radius_m);
  }
  return refine_range_m;
}

std::vector<FmcwRadar::RayCell> FmcwRadar::RefinedRays(const std::vector<double>& refine_range_m,
                                                       std::vector<int>& sub_of) const {
  const FmcwRadarConfig& c = config_;
  const double az0 = -0.5 * c.fov_azimuth_deg * kPi / 180.0;
  const double el0 = -0.5 * c.fov_elevation_deg * kPi / 180.0;
  const double cell_rad = std::max(d_az_rad_, d_el_rad_);
  sub_of.assign(grid_.size(), 0);
  std::vector<RayCell> fine;
  const Eigen::Matrix3d R_WR = X_WR_.linear();
  for (int j = 0; j < n_el_; ++j)
    for (int i = 0; i < n_az_; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * n_az_ + i;
      if (refine_range_m[k] == kNotRefined) continue;
      // n = min(64, ceil(R max(d_az, d_el) / object_ray_spacing_m)) rays per side.
      const int sub = static_cast<int>(
          std::clamp(std::ceil(refine_range_m[k] * cell_rad / c.object_ray_spacing_m), 1.0, 64.0));
      sub_of[k] = sub;
      for (int q = 0; q < sub; ++q) {
        const double el_lo = el0 + (j + static_cast<double>(q) / sub) * d_el_rad_;
        const double el_hi = el_lo + d_el_rad_ / sub;
        const double el = 0.5 * (el_lo + el_hi);
        // dOmega = d_az (sin el_hi - sin el_lo), the sub-cell's share.
        const double omega = d_az_rad_ / sub * (std::sin(el_hi) - std::sin(el_lo));
        for (int p = 0; p < sub; ++p) {
          const double az = az0 + (i + (p + 0.5) / sub) * d_az_rad_;
          const Eigen::Vector3d u(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                  std::sin(el));
          fine.push_back({(R_WR * u).cast<float>(), omega});
        }
      }
    }
  return fine;
}

void FmcwRadar::AddMultipath(std::vector<Scatterer>& scatterers) const {
  const Eigen::Vector3d o = X_WR_.translation();
  if (o.z() <= 0.0) return;
  const double rho2 = config_.multipath_reflection * config_.multipath_reflection;
  const std::size_t n = scatterers.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Scatterer s = scatterers[k];
    if (s.object < 1 || s.multipath || s.position_m.z() <= 0.0) continue;
    const Eigen::Vector3d image(s.position_m.x(), s.position_m.y(), -s.position_m.z());
    const Eigen::Vector3d image_v(s.velocity_mps.x(), s.velocity_mps.y(), -s.velocity_mps.z());
    const Eigen::Vector3d d = s.position_m - o, d_img = image - o;
    const double r = d.norm(), r_img = d_img.norm();
    const Eigen::Vector3d u = d / r, u_img = d_img / r_img;
    if (!InFieldOfView(u_img)) continue;
    // The specular point: where the line to the image crosses z = 0.
    const Eigen::Vector3d bounce = o + d_img * (o.z() / (o.z() - image.z()));
    // Ends are kept clear of the bounce point's ground and the object's own skin.
    if (scene_.Occluded(o, bounce, 0.05) || scene_.Occluded(bounce, s.position_m, 0.3)) continue;
    const double r_mix = 0.5 * (r + r_img);
    const double v_mix = 0.5 * (s.velocity_mps.dot(u) + image_v.dot(u_img));
    // sigma rho^2 R_mix^4 / (R^2 R'^2): the mixed path's 1 / (R R') amplitude
    // at its apparent range R_mix.
    const double rcs_mix = s.rcs_m2 * rho2 * std::pow(r_mix * r_mix / (r * r_img), 2);
    for (const Eigen::Vector3d& arrival : {u_img, u}) {
      Scatterer m;
      m.position_m = o + r_mix * arrival;
      m.velocity_mps = v_mix * arrival;
      m.rcs_m2 = rcs_mix;
      m.object = s.object;
      m.multipath = true;
      scatterers.push_back(m);
    }
    Scatterer both;
    both.position_m = image;
    both.velocity_mps = image_v;
    both.rcs_m2 = s.rcs_m2 * rho2 * rho2;
    both.object = s.object;
    both.multipath = true;
    scatterers.push_back(both);
  }
}

void FmcwRadar::AddRainClutter(double rain_mm_h, std::uint64_t frame_key, RadarCube& cube) const {
  const FmcwRadarConfig& c = config_;
  const double eta = RainReflectivityPerM(rain_mm_h);
  if (eta <= 0.0) return;
  const int ns = c.adc_samples, nc = c.chirps_per_frame, antennas = c.nx * c.ny;

  // Where the rain is visible: the free range of a 1-degree ray grid.
  const RainView view = CastRainView(c, scene_, X_WR_, max_range_m_);
  // Range bin b is centred on the FFT's bin b, [(b - 1/2), (b + 1/2)) dR;
  // beyond the last centre the beat would wrap to bin 0.
  const int first_bin =
      static_cast<int>(std::ceil(c.rain_clutter_min_range_m / range_bin_m_ - 0.5));
  if (first_bin >= ns) return;
  const std::array<double, kDropNodes> fall_mps = RainFallSpeeds(rain_mm_h);
  std::vector<double> power_weight;  // of each direction, for the covariance
  const std::vector<double> spectrum = RainSpectrum(*this, view, fall_mps, first_bin, power_weight);
  const std::vector<float> sigma = RainCellSigma(*this, rain_mm_h, eta, first_bin, spectrum);
  const std::optional<Eigen::MatrixXcd> mixing = RainSpatialMix(c, view, power_weight);
  if (!mixing) return;
  const Eigen::MatrixXcd& mix = *mixing;

  // Each independent field: complex Gaussian cells (range bin b, Doppler bin
  // d) taken to samples and chirps by the 2-D inverse DFT
  // sum_{d,b} G e^{j 2 pi (d c / Nc + b s / Ns)}, the header's beat and
  // Doppler phases at the bin centres.
  const std::size_t plane = static_cast<std::size_t>(ns) * nc;
  std::vector<std::complex<float>> fields(plane * antennas);
  tbb::parallel_for(0, antennas, [&](int a) {
    SplitMixEngine engine(core::Mix64(frame_key ^ kRainStreamSalt ^ core::Mix64(a)));
    boost::random::normal_distribution<float> normal(0.0f, 1.0f);
    std::complex<float>* g = fields.data() + plane * a;
    for (std::size_t i = 0; i < plane; ++i) {
      if (sigma[i] == 0.0f) continue;
      const float re = normal(engine), im = normal(engine);
      g[i] = {sigma[i] * re, sigma[i] * im};
    }
    rain_fft_->Inverse(g);
  });
  // The elements' fields mixed by the covariance's Cholesky factor, added to the cube.
  tbb::parallel_for(0, nc, [&](int ch) {
    for (int a = 0; a < antennas; ++a) {
      std::complex<float>* out = cube.data.data() + (static_cast<std::size_t>(a) * nc + ch) * ns;
      for (int a2 = 0; a2 <= a; ++a2) {
        const float mr = static_cast<float>(mix(a, a2).real());
        const float mi = static_cast<float>(mix(a, a2).imag());
        const std::complex<float>* x =
            fields.data() + plane * a2 + static_cast<std::size_t>(ch) * ns;
        for (int s = 0; s < ns; ++s)
          out[s] += std::complex<float>(mr * x[s].real() - mi * x[s].imag(),
                                        mr * x[s].imag() + mi * x[s].real());
      }
    }
  });
}

// Per echo (in group order), the separable factors of its samples:
// A[q] = a e^{j(4 pi R / lambda + w kFastBlock q)}, B[r] = e^{j w r}
// (w = 2 pi f_b / fs, sample s = kFastBlock q + r) and the element phasors
// e^{j 2 pi (ix dx u_y + iy dy u_z) / lambda}; per velocity group, its
// Doppler phasor at each chirp.
struct FmcwRadar::SampleFactors {
  int blocks = 0;                 // fast-time blocks of kFastBlock samples
  std::vector<float> a_re, a_im;  // [echo * blocks + q]
  std::vector<float> b_re, b_im;  // [echo * kFastBlock + r]
  std::vector<float> e_re, e_im;  // [echo * antennas + element]
  std::vector<float> z_re, z_im;  // [group * chirps + chirp]
};

std::vector<FmcwRadar::Echo> FmcwRadar::EchoesOf(const std::vector<Scatterer>& scatterers,
                                                 double rain_mm_h) const {
  const Eigen::Vector3d o = X_WR_.translation();
  std::vector<Echo> echoes;
  echoes.reserve(scatterers.size());
  for (const Scatterer& s : scatterers) {
    const Eigen::Vector3d d = s.position_m - o;
    const double r = d.norm();
    if (!(r >= kMinRangeM && r < max_range_m_) || !(s.rcs_m2 > 0.0)) continue;
    const Eigen::Vector3d u_W = d / r;
    echoes.push_back({r, s.velocity_mps.dot(u_W), R_RW_ * u_W, SnrPerSample(s.rcs_m2, r, rain_mm_h),
                      s.object == 0 && !s.multipath});
  }
  return echoes;
}

std::vector<std::size_t> FmcwRadar::VelocityGroups(const std::vector<Echo>& echoes,
                                                   std::vector<std::size_t>& order) {
  order.resize(echoes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return echoes[a].radial_velocity_mps < echoes[b].radial_velocity_mps;
  });
  std::vector<std::size_t> group_begin;
  for (std::size_t i = 0; i < order.size(); ++i)
    if (i == 0 || echoes[order[i]].radial_velocity_mps != echoes[order[i - 1]].radial_velocity_mps)
      group_begin.push_back(i);
  group_begin.push_back(order.size());
  return group_begin;
}

void FmcwRadar::FillEchoFactors(const std::vector<Echo>& echoes,
                                const std::vector<std::size_t>& order, const StaticPrefix& prefix,
                                SampleFactors& f) const {
  const FmcwRadarConfig& c = config_;
  const int nx = c.nx, ny = c.ny;
  const int antennas = nx * ny;
  const int blocks = f.blocks = (c.adc_samples + kFastBlock - 1) / kFastBlock;
  const std::size_t k_count = echoes.size();
  const double dx_m = c.spacing_x_wavelengths * lambda_m_;
  const double dy_m = c.spacing_y_wavelengths * lambda_m_;
  // Powers of one phasor are taken by repeated multiplication in double: a
  // few sincos per echo, and 1e-14 rad of accumulated error.
  std::vector<float>& a_re = f.a_re;
  std::vector<float>& a_im = f.a_im;
  std::vector<float>& b_re = f.b_re;
  std::vector<float>& b_im = f.b_im;
  std::vector<float>& e_re = f.e_re;
  std::vector<float>& e_im = f.e_im;
  a_re.resize(k_count * blocks), a_im.resize(k_count * blocks);
  b_re.resize(k_count * kFastBlock), b_im.resize(k_count * kFastBlock);
  e_re.resize(k_count * antennas), e_im.resize(k_count * antennas);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, k_count, 64),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          if (prefix.cached && i >= prefix.begin && i < prefix.begin + prefix.count) continue;
          const Echo& e = echoes[order[i]];
          // f_b = 2 K R / c
          const double f_b = 2.0 * slope_hz_per_s_ * e.range_m / kSpeedOfLight_mps;
          const double w = 2.0 * kPi * f_b / sample_rate_hz_;
          const std::complex<double> step = Phasor(w);
          std::complex<double> p = 1.0;
          for (int r = 0; r < kFastBlock; ++r, p *= step) {
            b_re[i * kFastBlock + r] = static_cast<float>(p.real());
            b_im[i * kFastBlock + r] = static_cast<float>(p.imag());
          }
          const std::complex<double> block_step = Phasor(w * kFastBlock);
          p = std::sqrt(e.snr) * Phasor(4.0 * kPi * e.range_m / lambda_m_);
          for (int q = 0; q < blocks; ++q, p *= block_step) {
            a_re[i * blocks + q] = static_cast<float>(p.real());
            a_im[i * blocks + q] = static_cast<float>(p.imag());
          }
          const std::complex<double> ex = Phasor(2.0 * kPi * dx_m * e.u_R.y() / lambda_m_);
          const std::complex<double> ey = Phasor(2.0 * kPi * dy_m * e.u_R.z() / lambda_m_);
          std::complex<double> py = 1.0;
          for (int iy = 0; iy < ny; ++iy, py *= ey) {
            std::complex<double> pxy = py;
            for (int ix = 0; ix < nx; ++ix, pxy *= ex) {
              e_re[i * antennas + iy * nx + ix] = static_cast<float>(pxy.real());
              e_im[i * antennas + iy * nx + ix] = static_cast<float>(pxy.imag());
            }
          }
        }
      });
}

void FmcwRadar::FillDopplerPhasors(const std::vector<Echo>& echoes,
                                   const std::vector<std::size_t>& order,
                                   const std::vector<std::size_t>& group_begin,
                                   SampleFactors& f) const {
  const int nc = config_.chirps_per_frame;
  const std::size_t groups = group_begin.size() - 1;
  std::vector<float>& z_re = f.z_re;
  std::vector<float>& z_im = f.z_im;
  // Doppler phasor of each group at each chirp: e^{j 2 pi (2 v / lambda) c T_c}.
  z_re.resize(groups * nc), z_im.resize(groups * nc);
  for (std::size_t g = 0; g < groups; ++g) {
    const double v = echoes[order[group_begin[g]]].radial_velocity_mps;
    for (int ch = 0; ch < nc; ++ch) {
      const std::complex<double> z =
          Phasor(2.0 * kPi * (2.0 * v / lambda_m_) * ch * chirp_period_s_);
      z_re[g * nc + ch] = static_cast<float>(z.real());
      z_im[g * nc + ch] = static_cast<float>(z.imag());
    }
  }
}

void FmcwRadar::SumSignals(const SampleFactors& f, const std::vector<std::size_t>& group_begin,
                           const StaticPrefix& prefix, std::uint64_t frame_key,
                           RadarCube& cube) const {
  const FmcwRadarConfig& c = config_;
  const int ns = c.adc_samples, nc = c.chirps_per_frame;
  const int antennas = c.nx * c.ny;
  const int blocks = f.blocks;
  const std::size_t groups = group_begin.size() - 1;
  const std::vector<float>& a_re = f.a_re;
  const std::vector<float>& a_im = f.a_im;
  const std::vector<float>& b_re = f.b_re;
  const std::vector<float>& b_im = f.b_im;
  const std::vector<float>& e_re = f.e_re;
  const std::vector<float>& e_im = f.e_im;
  const std::vector<float>& z_re = f.z_re;
  const std::vector<float>& z_im = f.z_im;
  const std::size_t padded = static_cast<std::size_t>(blocks) * kFastBlock;
  tbb::parallel_for(0, antennas, [&](int ant) {
    // Fast-time sum of each group at this antenna.
    std::vector<float> s_re(groups * padded, 0.0f), s_im(groups * padded, 0.0f);
    const auto accumulate = [&](std::size_t g, std::size_t from, std::size_t to) {
      for (std::size_t i = from; i < to; ++i) {
        const float er = e_re[i * antennas + ant], ei = e_im[i * antennas + ant];
        for (int q = 0; q < blocks; ++q) {
          const float ar = a_re[i * blocks + q], ai = a_im[i * blocks + q];
          AccumulateBlock(er * ar - ei * ai, er * ai + ei * ar, &b_re[i * kFastBlock],
                          &b_im[i * kFastBlock], &s_re[g * padded + q * kFastBlock],
                          &s_im[g * padded + q * kFastBlock]);
        }
      }
    };
    const std::size_t kept = static_cast<std::size_t>(ant) * padded;
    for (std::size_t g = 0; g < groups; ++g) {
      std::size_t from = group_begin[g];
      if (prefix.count > 0 && g == prefix.group) {
        from += prefix.count;
        float* sr = &s_re[g * padded];
        float* si = &s_im[g * padded];
        if (prefix.cached) {
          std::copy_n(&static_sums_->s_re[kept], padded, sr);
          std::copy_n(&static_sums_->s_im[kept], padded, si);
        } else {
          accumulate(g, group_begin[g], from);
          if (static_cache_) {
            std::copy_n(sr, padded, &static_sums_->s_re[kept]);
            std::copy_n(si, padded, &static_sums_->s_im[kept]);
          }
        }
      }
      accumulate(g, from, group_begin[g + 1]);
    }
    std::vector<float> row_re(padded), row_im(padded);
    boost::random::normal_distribution<float> normal(0.0f, static_cast<float>(std::sqrt(0.5)));
    for (int ch = 0; ch < nc; ++ch) {
      std::fill(row_re.begin(), row_re.end(), 0.0f);
      std::fill(row_im.begin(), row_im.end(), 0.0f);
      for (std::size_t g = 0; g < groups; ++g)
        for (int q = 0; q < blocks; ++q)
          AccumulateBlock(z_re[g * nc + ch], z_im[g * nc + ch], &s_re[g * padded + q * kFastBlock],
                          &s_im[g * padded + q * kFastBlock], &row_re[q * kFastBlock],
                          &row_im[q * kFastBlock]);
      std::complex<float>* out = cube.data.data() + (static_cast<std::size_t>(ant) * nc + ch) * ns;
      if (c.thermal_noise) {
        SplitMixEngine engine(
            core::Mix64(frame_key ^ core::Mix64(static_cast<std::uint64_t>(ant) * nc + ch)));
        for (int s = 0; s < ns; ++s) {
          const float n_re = normal(engine);
          const float n_im = normal(engine);
          out[s] = {row_re[s] + n_re, row_im[s] + n_im};
        }
      } else {
        for (int s = 0; s < ns; ++s) out[s] = {row_re[s], row_im[s]};
      }
    }
  });
}

FmcwRadar::StaticPrefix FmcwRadar::FindStaticPrefix(const std::vector<Echo>& echoes,
                                                    const std::vector<std::size_t>& order,
                                                    const std::vector<std::size_t>& group_begin) {
  StaticPrefix p;
  const std::size_t count = static_cast<std::size_t>(
      std::count_if(echoes.begin(), echoes.end(), [](const Echo& e) { return e.static_world; }));
  std::size_t first = 0;
  while (first < order.size() && !echoes[order[first]].static_world) ++first;
  if (count == 0 || first + count > order.size()) return p;
  const auto g = std::upper_bound(group_begin.begin(), group_begin.end(), first) - 1;
  if (*g != first || *(g + 1) < first + count) return p;  // not the lead of its group
  for (std::size_t j = first; j < first + count; ++j)
    if (!echoes[order[j]].static_world) return p;
  p.group = static_cast<std::size_t>(g - group_begin.begin());
  p.begin = first;
  p.count = count;
  return p;
}

std::size_t FmcwRadar::static_sum_hits() const {
  const std::lock_guard<std::mutex> lock(static_sums_->mutex);
  return static_sums_->hits;
}

RadarCube FmcwRadar::Synthesize(const std::vector<Scatterer>& scatterers,
                                const core::WeatherConfig& weather, core::RngStream& noise) const {
  const FmcwRadarConfig& c = config_;
  const std::uint64_t frame_key = noise.NextU64();
  const std::vector<Echo> echoes = EchoesOf(scatterers, weather.rain_mm_h);

  // Echoes of equal radial velocity share one Doppler progression, so each
  // antenna sums their fast-time signals once and spreads the sum over the
  // chirps: the static world costs one fast-time row per antenna.
  std::vector<std::size_t> order;
  const std::vector<std::size_t> group_begin = VelocityGroups(echoes, order);
  StaticPrefix prefix = FindStaticPrefix(echoes, order, group_begin);
  StaticSums& kept = *static_sums_;
  const std::lock_guard<std::mutex> lock(kept.mutex);
  if (static_cache_ && prefix.count > 0) {
    prefix.cached = kept.echoes.size() == prefix.count;
    for (std::size_t j = 0; prefix.cached && j < prefix.count; ++j)
      prefix.cached = echoes[order[prefix.begin + j]].SameAs(kept.echoes[j]);
    if (!prefix.cached) {
      const std::size_t padded =
          static_cast<std::size_t>((c.adc_samples + kFastBlock - 1) / kFastBlock) * kFastBlock;
      kept.echoes.clear();
      for (std::size_t j = 0; j < prefix.count; ++j)
        kept.echoes.push_back(echoes[order[prefix.begin + j]]);
      kept.s_re.assign(static_cast<std::size_t>(c.nx * c.ny) * padded, 0.0f);
      kept.s_im.assign(kept.s_re.size(), 0.0f);
    }
    kept.hits += prefix.cached;
  }

  SampleFactors factors;
  FillEchoFactors(echoes, order, prefix, factors);
  FillDopplerPhasors(echoes, order, group_begin, factors);

  RadarCube cube;
  cube.Resize(c.adc_samples, c.chirps_per_frame, c.nx, c.ny);
  SumSignals(factors, group_begin, prefix, frame_key, cube);
  if (weather.rain_mm_h > 0.0 && c.rain_clutter) AddRainClutter(weather.rain_mm_h, frame_key, cube);
  return cube;
}

}  // namespace uavsim::sensors
