#include "sensors/lidar.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/physical_constants.h"

namespace uavsim::sensors {
namespace {

using core::kPi;
using core::kSpeedOfLight_mps;

// Rosette prism rates. Their ratio is the golden ratio, the "most
// irrational" number, so the rose never closes; f1 + f2 = 196.8 Hz gives
// about 20 passes through the centre in a 10 Hz frame.
constexpr double kPrism1Hz = 121.6;
constexpr double kPrism2Hz = kPrism1Hz / 1.6180339887498949;

// Mid-360-like scan (lidar.h): azimuth turns and elevation triangle-wave cycles per second.
constexpr double kMid360AzimuthHz = 16.180339887498949;    // 10 x golden ratio
constexpr double kMid360ElevationHz = 2236.0679774997897;  // 1000 x sqrt(5)

// Rain (LISA, Kilic et al. 2021): Marshall-Palmer and water at 905 nm.
constexpr double kMinDropMm = 0.05;  // LISA's smallest sampled drop; MP is wrong below
constexpr double kMaxDropMm = 10.0;  // drops break up above ~8 mm

// A fog echo faded to more than this many times its mean has probability
// e^-60 with one speckle cell and less with more (Chernoff: below
// exp(-M (60 - 1 - ln 60))): the fog profile is tabulated only where it
// could still be detected.
constexpr double kMaxFade = 60.0;

// Transmitter/receiver overlap xi(r) of a biaxial sensor (Hahner et al.,
// linear between r_1 and r_2).
struct Overlap {
  double r1_m, r2_m;
  double operator()(double r_m) const {
    if (r_m < r1_m) return 0.0;
    if (r_m >= r2_m) return 1.0;
    return (r_m - r1_m) / (r2_m - r1_m);
  }
};

// A function of range tabulated on an even grid, with its running integral,
// so that draws from it (as a density) cost two binary searches.
struct RangeTable {
  double r0_m = 0.0, step_m = 1.0;
  std::vector<double> value;       // f(r_j)
  std::vector<double> cumulative;  // integral of f from r0 to r_j (trapezoid)

  double end_m() const { return r0_m + step_m * static_cast<double>(value.size() - 1); }

  void Fill(double r0, double r1, double step, const std::function<double(double)>& f) {
    r0_m = r0;
    const auto n = static_cast<std::size_t>(std::ceil((r1 - r0) / step)) + 1;
    step_m = n > 1 ? (r1 - r0) / static_cast<double>(n - 1) : 1.0;
    value.resize(n);
    cumulative.assign(n, 0.0);
    for (std::size_t j = 0; j < n; ++j) value[j] = f(r0 + step_m * static_cast<double>(j));
    for (std::size_t j = 1; j < n; ++j)
      cumulative[j] = cumulative[j - 1] + 0.5 * step_m * (value[j - 1] + value[j]);
  }

  double Interp(const std::vector<double>& y, double r_m) const {
    const double x = (r_m - r0_m) / step_m;
    if (x <= 0.0) return y.front();
    const auto j = static_cast<std::size_t>(x);
    if (j + 1 >= y.size()) return y.back();
    const double w = x - static_cast<double>(j);
    return y[j] * (1.0 - w) + y[j + 1] * w;
  }
  double Cumulative(double r_m) const { return Interp(cumulative, r_m); }
  double Value(double r_m) const { return Interp(value, r_m); }

  // The range where the running integral reaches c (clamped to the grid).
  double InverseCumulative(double c) const {
    const auto it = std::lower_bound(cumulative.begin(), cumulative.end(), c);
    if (it == cumulative.begin()) return r0_m;
    if (it == cumulative.end()) return end_m();
    const auto j = static_cast<std::size_t>(it - cumulative.begin());
    const double lo = cumulative[j - 1], hi = cumulative[j];
    const double w = hi > lo ? (c - lo) / (hi - lo) : 0.0;
    return r0_m + step_m * (static_cast<double>(j - 1) + w);
  }
};

// The weather's effect on one frame: extinction and the backscatter tables.
struct Atmosphere {
  double alpha_per_m = 0.0;
  bool fog = false;
  RangeTable fog_echo;  // mean fog echo S(r), normalised power
  std::size_t fog_peak = 0;
  bool rain = false;
  RangeTable rain_drops;  // detectable drops per metre of beam, lambda(r)
  double rain_lambda_per_mm = 0.0;

  bool active() const { return fog || rain; }
};

struct Echo {
  double range_m = 0.0;
  double power = 0.0;
  bool spurious = false;
};

std::uint64_t PoissonDraw(double mean, core::RngStream& rng) {
  if (mean <= 0.0) return 0;
  if (mean > 50.0) {  // normal approximation; inversion would underflow e^-mean
    const double k = std::round(mean + std::sqrt(mean) * rng.Normal());
    return k > 0.0 ? static_cast<std::uint64_t>(k) : 0;
  }
  double p = std::exp(-mean), cdf = p;
  const double u = rng.Uniform();
  std::uint64_t k = 0;
  while (u > cdf && k < 1000) {
    ++k;
    p *= mean / static_cast<double>(k);
    cdf += p;
  }
  return k;
}

void Require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("LidarConfig: " + message);
}

// The fog's mean echo S(r) = rho_v xi(r) exp(-2 alpha r) / r^2 (Hahner et al.
// 2021), tabulated from r_lo to where no fade could still lift it to P_th.
void FillFogEcho(Atmosphere& atm, const LidarConfig& c, double visibility_m, const Overlap& overlap,
                 double p_th, double r_lim, double r_lo) {
  const double alpha = atm.alpha_per_m;
  atm.fog = true;
  const double beta = kFogBackscatterTimesVisibility / visibility_m;
  // rho_v = pi beta c tau / 2: one range cell of fog as a Lambertian target.
  const double rho_v = kPi * beta * kSpeedOfLight_mps * c.pulse_width_ns * 1e-9 / 2.0;
  // Past full overlap S(r) <= rho_v / r^2, so beyond this no fade is detected.
  const double r_end =
      std::min(r_lim, std::max(c.full_overlap_range_m, std::sqrt(kMaxFade * rho_v / p_th)));
  atm.fog_echo.Fill(
      r_lo, std::max(r_end, r_lo + 0.01), std::max(0.01, (r_end - r_lo) / 8192.0),
      [&](double r) { return rho_v * overlap(r) * std::exp(-2.0 * alpha * r) / (r * r); });
  const auto& v = atm.fog_echo.value;
  atm.fog_peak = static_cast<std::size_t>(std::max_element(v.begin(), v.end()) - v.begin());
}

// The rain's detectable drops per metre of beam, lambda(r): the
// Marshall-Palmer tail above the smallest drop still detectable at r, in the
// beam's cone (LISA, Kilic et al. 2021), out to where that drop passes the
// largest drop that exists.
void FillRainDrops(Atmosphere& atm, const LidarConfig& c, double rain_mm_h, const Overlap& overlap,
                   double p_th, double r_lim, double r_lo) {
  const double alpha = atm.alpha_per_m;
  atm.rain = true;
  const double lambda = MarshallPalmerLambdaPerMm(rain_mm_h);
  atm.rain_lambda_per_mm = lambda;
  const double theta = c.beam_divergence_mrad * 1e-3;
  // The smallest detectable drop grows as r^2, so drops are detectable only
  // up to where it passes the largest drop that exists.
  double r_end = r_lo;
  while (r_end < r_lim) {
    r_end += 0.05;
    const double xi = overlap(r_end);
    if (r_end < c.full_overlap_range_m || xi <= 0.0) continue;
    const double d_min_mm = 1e3 * theta * r_end * r_end *
                            std::sqrt(p_th * std::exp(2.0 * alpha * r_end) / kWaterFresnel);
    if (d_min_mm > kMaxDropMm) break;
  }
  r_end = std::min(r_end, r_lim);
  atm.rain_drops.Fill(r_lo, std::max(r_end, r_lo + 0.01), 0.02, [&](double r) {
    const double xi = overlap(r);
    if (xi <= 0.0) return 0.0;
    // A drop filling the beam returns rho_w xi e^{-2 alpha r} / r^2; smaller
    // drops return their share (D / theta r)^2 of it.
    const double fill = std::sqrt(p_th * r * r * std::exp(2.0 * alpha * r) / (kWaterFresnel * xi));
    if (fill >= 1.0) return 0.0;
    const double d_min_mm = std::max(kMinDropMm, 1e3 * theta * r * fill);
    const double cone_area_m2 = kPi * theta * theta * r * r / 4.0;
    // N0 / Lambda e^{-Lambda D_min}: Marshall-Palmer drops larger than D_min per m^3.
    return cone_area_m2 * kMarshallPalmerN0 / lambda * std::exp(-lambda * d_min_mm);
  });
}

// The weather's effect on one frame: extinction and the backscatter tables.
Atmosphere MakeAtmosphere(const LidarConfig& c, const core::WeatherConfig& weather,
                          const Overlap& overlap, double p_th, double r_lim, double r_lo) {
  Atmosphere atm;
  atm.alpha_per_m = AtmosphericExtinctionPerM(weather);
  if (weather.fog_visibility_m)
    FillFogEcho(atm, c, *weather.fog_visibility_m, overlap, p_th, r_lim, r_lo);
  if (weather.rain_mm_h > 0.0) FillRainDrops(atm, c, weather.rain_mm_h, overlap, p_th, r_lim, r_lo);
  return atm;
}

// The frame's constants each beam reads to turn its hit into a point.
struct BeamShading {
  const LidarConfig& c;
  const RaycastScene& scene;
  const Atmosphere& atm;
  Overlap overlap;
  double p_th, r_lim, speckle_cells;
  std::uint64_t frame_key;
  bool needs_rng;
  float sat2;  // saturation_range_m^2
  Eigen::Vector3f origin_w;

  // Keeps e if it beats `best` under the return mode.
  void Offer(const Echo& e, std::optional<Echo>& best) const {
    if (!best || (c.return_mode == LidarReturnMode::kStrongest ? e.power > best->power
                                                               : e.range_m > best->range_m))
      best = e;
  }

  // The fog echo of a beam whose hard target (if any) is at hit_m: a speckle
  // fade E, then a range drawn from S over the part above P_th / E.
  void FogEcho(double hit_m, core::RngStream& rng, std::optional<Echo>& best) const {
    const RangeTable& f = atm.fog_echo;
    const double fade = FogSpeckleFade(speckle_cells, rng);
    const double level = p_th / fade;
    if (f.value[atm.fog_peak] >= level) {
      // S rises to its peak and falls after it: the part above `level` is
      // one interval around the peak.
      const auto rise_end = f.value.begin() + static_cast<std::ptrdiff_t>(atm.fog_peak) + 1;
      const auto first = std::lower_bound(f.value.begin(), rise_end, level);
      const auto last = std::lower_bound(rise_end - 1, f.value.end(), level,
                                         [](double s, double lv) { return s >= lv; });
      const double r_a = f.r0_m + f.step_m * static_cast<double>(first - f.value.begin());
      const double r_b =
          std::min(hit_m, f.r0_m + f.step_m * static_cast<double>(last - f.value.begin() - 1));
      const double u = rng.Uniform();
      if (r_b > r_a) {
        const double ca = f.Cumulative(r_a), cb = f.Cumulative(r_b);
        const double r = f.InverseCumulative(ca + u * (cb - ca));
        Offer({r, std::max(p_th, fade * f.Value(r)), true}, best);
      }
    }
  }

  // The rain echoes of a beam whose hard target (if any) is at hit_m: a
  // Poisson number of detectable drops in front of it, each at a range drawn
  // from lambda(r) and of a diameter drawn from the Marshall-Palmer tail.
  void RainEchoes(double hit_m, core::RngStream& rng, std::optional<Echo>& best) const {
    const double alpha = atm.alpha_per_m;
    const RangeTable& d = atm.rain_drops;
    const double r_end = std::min(hit_m, d.end_m());
    const double mean = r_end > d.r0_m ? d.Cumulative(r_end) : 0.0;
    const std::uint64_t drops = PoissonDraw(mean, rng);
    const double theta = c.beam_divergence_mrad * 1e-3;
    for (std::uint64_t k = 0; k < drops; ++k) {
      const double r = d.InverseCumulative(rng.Uniform() * mean);
      const double xi = overlap(r);
      const double e2 = std::exp(-2.0 * alpha * r);
      const double fill = std::sqrt(p_th * r * r / (e2 * kWaterFresnel * std::max(xi, 1e-12)));
      const double d_min_mm = std::max(kMinDropMm, 1e3 * theta * r * fill);
      // The Marshall-Palmer tail above d_min is exponential again.
      const double d_mm = d_min_mm + rng.Exponential(1.0 / atm.rain_lambda_per_mm);
      const double ratio = d_mm * 1e-3 / (theta * r);
      const double share = std::min(1.0, ratio * ratio);
      // LISA: P = rho_w min((D / (theta r))^2, 1) xi(r) exp(-2 alpha r) / r^2.
      Offer({r, std::max(p_th, kWaterFresnel * share * xi * e2 / (r * r)), true}, best);
    }
  }

  // Beam i (ray, hit, firing time): its point into `slot` and kind 0 (no
  // return), 1 (target) or 2 (spurious) into `kind`.
  void Beam(std::size_t i, const Ray& ray, const RayHit& h, float time, LidarPoint& slot,
            std::uint8_t& kind) const {
    const double alpha = atm.alpha_per_m;
    std::optional<Echo> best;
    double hit_m = r_lim;
    if (h.hit()) {
      hit_m = h.t;
      const double rho = std::clamp(scene.material(h.material).lidar_reflectivity, 0.0, 1.0);
      const double cos_i = std::abs(static_cast<double>(h.normal_w.dot(ray.direction)));
      // P(R) = rho cos(i) xi(R) exp(-2 alpha R) / R^2 (lidar.h).
      const double power =
          rho * cos_i * overlap(hit_m) * std::exp(-2.0 * alpha * hit_m) / (hit_m * hit_m);
      if (power >= p_th) best = Echo{hit_m, power, false};
    }
    if (!best && !atm.active()) return;
    std::optional<core::RngStream> rng;
    if (needs_rng) rng.emplace(core::Mix64(frame_key ^ core::Mix64(i)));
    if (atm.active()) {
      if (atm.fog) FogEcho(hit_m, *rng, best);
      if (atm.rain) RainEchoes(hit_m, *rng, best);
    }
    if (!best) return;
    if (c.dropout > 0.0 && rng->Bernoulli(c.dropout)) return;
    double range_m = best->range_m;
    if (c.range_noise_m > 0.0) range_m += c.range_noise_m * rng->Normal();
    const Eigen::Vector3f p = origin_w + ray.direction * static_cast<float>(range_m);
    slot = {p.x(), p.y(), p.z(), std::min(1.0f, static_cast<float>(best->power) * sat2), time};
    kind = best->spurious ? 2 : 1;
  }
};

// The frame of the beams' points (kinds: 0 no return, 1 target, 2 spurious),
// in beam order.
PointCloudFrame CollectPoints(double t_start_s, const std::vector<LidarPoint>& slots,
                              const std::vector<std::uint8_t>& kinds) {
  PointCloudFrame frame;
  frame.t_start_s = t_start_s;
  frame.rays_cast = slots.size();
  std::size_t count = 0;
  for (std::uint8_t k : kinds) count += k != 0;
  frame.points.reserve(count);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (kinds[i] == 0) continue;
    frame.points.push_back(slots[i]);
    frame.spurious += kinds[i] == 2;
  }
  return frame;
}

}  // namespace

Lidar::Lidar(const LidarConfig& config, RaycastScene& scene) : config_(config), scene_(scene) {
  const LidarConfig& c = config_;
  Require(c.timing.rate_hz > 0.0, "rate_hz must be positive");
  Require(c.max_range_m > 0.0, "max_range_m must be positive");
  Require(c.reference_reflectivity > 0.0 && c.reference_reflectivity <= 1.0,
          "reference_reflectivity must be in (0, 1]");
  Require(c.min_range_m >= 0.0 && c.full_overlap_range_m >= c.min_range_m,
          "full_overlap_range_m must be at least min_range_m >= 0");
  Require(c.full_overlap_range_m < c.max_range_m, "full_overlap_range_m must be below max_range_m");
  Require(c.range_noise_m >= 0.0, "range_noise_m must be non-negative");
  Require(c.dropout >= 0.0 && c.dropout < 1.0, "dropout must be in [0, 1)");
  Require(c.saturation_range_m > 0.0 && c.pulse_width_ns > 0.0 && c.beam_divergence_mrad > 0.0,
          "saturation_range_m, pulse_width_ns and beam_divergence_mrad must be positive");
  Require(c.receiver_aperture_mm > 0.0, "receiver_aperture_mm must be positive");
  Require(c.time_slices_per_frame >= 1, "time_slices_per_frame must be at least 1");
  Require(c.RaysPerFrame() >= 1.0 && c.RaysPerFrame() <= 1e9,
          "a frame must cast between 1 and 1e9 rays");

  const Eigen::Isometry3d X_WS = c.pose.ToIsometry();
  R_WS_ = X_WS.linear().cast<float>();
  origin_w_ = X_WS.translation().cast<float>();
  period_s_ = 1.0 / c.timing.rate_hz;
  threshold_ = c.reference_reflectivity / (c.max_range_m * c.max_range_m);
  ray_length_m_ = static_cast<float>(c.max_range_m / std::sqrt(c.reference_reflectivity));
  beam_count_ = static_cast<std::size_t>(c.RaysPerFrame());

  if (c.preset == LidarPreset::kSpinning32) {
    Require(c.channels >= 1, "channels must be at least 1");
    Require(c.vertical_angles_deg.empty() ||
                static_cast<int>(c.vertical_angles_deg.size()) == c.channels,
            "vertical_angles_deg must have one angle per channel");
    Require(c.azimuth_resolution_deg > 0.0, "azimuth_resolution_deg must be positive");
    for (int ch = 0; ch < c.channels; ++ch) {
      double el_deg = 0.5 * (c.vertical_min_deg + c.vertical_max_deg);
      if (!c.vertical_angles_deg.empty())
        el_deg = c.vertical_angles_deg[ch];
      else if (c.channels > 1)
        el_deg =
            c.vertical_min_deg + (c.vertical_max_deg - c.vertical_min_deg) * ch / (c.channels - 1);
      cos_el_.push_back(static_cast<float>(std::cos(el_deg * kPi / 180.0)));
      sin_el_.push_back(static_cast<float>(std::sin(el_deg * kPi / 180.0)));
    }
    columns_ = beam_count_ / static_cast<std::size_t>(c.channels);
    for (std::size_t k = 0; k < columns_; ++k) {
      const double az = 2.0 * kPi * static_cast<double>(k) / static_cast<double>(columns_);
      cos_az_.push_back(static_cast<float>(std::cos(az)));
      sin_az_.push_back(static_cast<float>(std::sin(az)));
    }
  } else {
    Require(c.points_per_s > 0.0, "points_per_s must be positive");
    if (c.preset == LidarPreset::kLivoxRosette)
      Require(c.fov_deg > 0.0 && c.fov_deg <= 180.0, "fov_deg must be in (0, 180]");
  }

  // Slices split the sweep evenly in time; blocks of at most kBlockBeams
  // beams tile each slice from its start. The partition depends on the
  // config alone, so packets hold the same rays however threads share them.
  const auto slices = static_cast<std::size_t>(c.time_slices_per_frame);
  std::size_t begin = 0;
  for (std::size_t s = 1; s <= slices && begin < beam_count_; ++s) {
    std::size_t end = beam_count_;
    if (s < slices) {
      // First beam fired at or after the slice's end; beam times never decrease.
      const double t_end = period_s_ * static_cast<double>(s) / static_cast<double>(slices);
      std::size_t lo = begin, hi = beam_count_;
      while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (BeamTime(mid) < t_end)
          lo = mid + 1;
        else
          hi = mid;
      }
      end = lo;
    }
    if (end == begin) continue;
    slice_blocks_.push_back(blocks_.size());
    for (std::size_t b = begin; b < end; b += kBlockBeams)
      blocks_.push_back({b, std::min(end, b + kBlockBeams)});
    begin = end;
  }
  slice_blocks_.push_back(blocks_.size());
}

double Lidar::BeamTime(std::size_t i) const {
  if (config_.preset != LidarPreset::kSpinning32)
    return static_cast<double>(i) / config_.points_per_s;
  const std::size_t column = i / static_cast<std::size_t>(config_.channels);
  return period_s_ * static_cast<double>(column) / static_cast<double>(columns_);
}

void Lidar::BlockRays(std::size_t begin, std::size_t end, double t_start_s, Ray* rays,
                      float* times) const {
  for (std::size_t i = begin; i < end; ++i) {
    Ray& r = rays[i - begin];
    r.origin_m = origin_w_;
    r.t_min = 1e-3f;
    r.t_max = ray_length_m_;
    times[i - begin] = static_cast<float>(BeamTime(i));
  }
  if (config_.preset == LidarPreset::kSpinning32) {
    const auto ch = static_cast<std::size_t>(config_.channels);
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t k = i / ch, c = i % ch;
      rays[i - begin].direction =
          R_WS_ * Eigen::Vector3f(cos_el_[c] * cos_az_[k], cos_el_[c] * sin_az_[k], sin_el_[c]);
    }
    return;
  }
  if (config_.preset == LidarPreset::kLivoxMid360) {
    // Fractional turns and cycles at the frame start (exact for hours of
    // simulated time), then per beam from its offset into the frame.
    const double a0 = kMid360AzimuthHz * t_start_s - std::floor(kMid360AzimuthHz * t_start_s);
    const double e0 = kMid360ElevationHz * t_start_s - std::floor(kMid360ElevationHz * t_start_s);
    const double el_lo = kMid360MinElevationDeg * kPi / 180.0;
    const double el_span = (kMid360MaxElevationDeg - kMid360MinElevationDeg) * kPi / 180.0;
    for (std::size_t i = begin; i < end; ++i) {
      const double t = BeamTime(i);
      const double az = 2.0 * kPi * (a0 + kMid360AzimuthHz * t);
      const double u = e0 + kMid360ElevationHz * t;
      const double el = el_lo + el_span * (1.0 - std::abs(1.0 - 2.0 * (u - std::floor(u))));
      rays[i - begin].direction = R_WS_ * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                          std::cos(el) * std::sin(az), std::sin(el))
                                              .cast<float>();
    }
    return;
  }
  // Rosette: the prisms' phases from their fractional turns at the frame
  // start (hours of simulated time keep full precision), evaluated exactly
  // at the block's first beam and advanced by rotation within the block.
  const double a1 = kPrism1Hz * t_start_s - std::floor(kPrism1Hz * t_start_s);
  const double a2 = kPrism2Hz * t_start_s - std::floor(kPrism2Hz * t_start_s);
  const double t0 = BeamTime(begin);
  const double p1 = 2.0 * kPi * (a1 + kPrism1Hz * t0), p2 = 2.0 * kPi * (a2 + kPrism2Hz * t0);
  double c1 = std::cos(p1), s1 = std::sin(p1), c2 = std::cos(p2), s2 = std::sin(p2);
  const double dp1 = 2.0 * kPi * kPrism1Hz / config_.points_per_s;
  const double dp2 = 2.0 * kPi * kPrism2Hz / config_.points_per_s;
  const double cd1 = std::cos(dp1), sd1 = std::sin(dp1), cd2 = std::cos(dp2), sd2 = std::sin(dp2);
  // Each prism deflects by half the half-fov; the two add in angle space.
  const double q = 0.25 * config_.fov_deg * kPi / 180.0;
  for (std::size_t i = begin; i < end; ++i) {
    const double dy = q * (c1 + c2), dz = q * (s1 - s2);
    const double theta = std::hypot(dy, dz);
    const double sinc = theta > 0.0 ? std::sin(theta) / theta : 1.0;
    rays[i - begin].direction =
        R_WS_ * Eigen::Vector3d(std::cos(theta), sinc * dy, sinc * dz).cast<float>();
    const double c1n = c1 * cd1 - s1 * sd1, c2n = c2 * cd2 - s2 * sd2;
    s1 = s1 * cd1 + c1 * sd1;
    s2 = s2 * cd2 + c2 * sd2;
    c1 = c1n;
    c2 = c2n;
  }
}

std::vector<LidarBeam> Lidar::Beams(double t_start_s) const {
  std::vector<LidarBeam> beams(beam_count_);
  std::array<Ray, kBlockBeams> rays;
  std::array<float, kBlockBeams> times;
  for (const Block& b : blocks_) {
    BlockRays(b.begin, b.end, t_start_s, rays.data(), times.data());
    for (std::size_t i = b.begin; i < b.end; ++i)
      beams[i] = {rays[i - b.begin], times[i - b.begin]};
  }
  return beams;
}

PointCloudFrame Lidar::Capture(double t_start_s, const core::WeatherConfig& weather,
                               core::RngStream& noise) {
  return DoCapture(t_start_s, weather, noise, false);
}

PointCloudFrame Lidar::CaptureStatic(double t_start_s, const core::WeatherConfig& weather,
                                     core::RngStream& noise) {
  return DoCapture(t_start_s, weather, noise, true);
}

PointCloudFrame Lidar::DoCapture(double t_start_s, const core::WeatherConfig& weather,
                                 core::RngStream& noise, bool static_only) {
  const LidarConfig& c = config_;
  const std::uint64_t frame_key = noise.NextU64();
  const Overlap overlap{c.min_range_m, c.full_overlap_range_m};
  const double r_lo = std::max(c.min_range_m, 0.01);
  const Atmosphere atm = MakeAtmosphere(c, weather, overlap, threshold_, ray_length_m_, r_lo);
  const bool needs_rng = c.range_noise_m > 0.0 || c.dropout > 0.0 || atm.active();
  const float sat2 = static_cast<float>(c.saturation_range_m * c.saturation_range_m);
  const BeamShading shading{
      c,         scene_,    atm,  overlap,  threshold_, ray_length_m_, FogSpeckleCells(c),
      frame_key, needs_rng, sat2, origin_w_};

  std::vector<LidarPoint> slots(beam_count_);
  std::vector<std::uint8_t> kinds(beam_count_, 0);  // 0: no return, 1: target, 2: spurious
  auto process_block = [&](std::size_t begin, std::size_t end) {
    std::array<Ray, kBlockBeams> rays;
    std::array<RayHit, kBlockBeams> hits;
    std::array<float, kBlockBeams> times;
    const std::size_t n = end - begin;
    BlockRays(begin, end, t_start_s, rays.data(), times.data());
    if (static_only)
      scene_.IntersectManyStatic(rays.data(), hits.data(), n);
    else
      scene_.IntersectMany(rays.data(), hits.data(), n);
    for (std::size_t j = 0; j < n; ++j)
      shading.Beam(begin + j, rays[j], hits[j], times[j], slots[begin + j], kinds[begin + j]);
  };

  auto run_blocks = [&](std::size_t first, std::size_t last) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t b = r.begin(); b != r.end(); ++b)
                          process_block(blocks_[b].begin, blocks_[b].end);
                      });
  };
  if (static_only || scene_.moving_object_count() == 0) {
    run_blocks(0, blocks_.size());
  } else {
    for (std::size_t s = 0; s + 1 < slice_blocks_.size(); ++s) {
      const std::size_t first = slice_blocks_[s], last = slice_blocks_[s + 1];
      scene_.SetTime(t_start_s +
                     0.5 * (BeamTime(blocks_[first].begin) + BeamTime(blocks_[last - 1].end - 1)));
      run_blocks(first, last);
    }
  }
  return CollectPoints(t_start_s, slots, kinds);
}

}  // namespace uavsim::sensors
