// LiDAR model against closed forms: plane and box distances, analytic beam
// counts, binomial dropout, Beer-Lambert detection range in fog and rain,
// backscatter, 1/R^2 intensity, motion smear, determinism, the rosette, and
// the PLY encoding. Expected values are computed here from geometry and the
// cited formulas, never taken from the model's own output.
#include "sensors/lidar.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <functional>
#include <set>
#include <string>
#include <vector>
#include "test_support.h"

#include "core/error.h"
#include "core/json_io.h"
#include "sensors/ply_io.h"

using uavsim::core::Material;
using uavsim::core::RadarClass;
using uavsim::core::RngStream;
using uavsim::core::TriangleMesh;
using uavsim::core::WeatherConfig;
using uavsim::core::WorldGeometry;
using uavsim::sensors::Lidar;
using uavsim::sensors::LidarConfig;
using uavsim::sensors::LidarPoint;
using uavsim::sensors::LidarPreset;
using uavsim::sensors::LidarReturnMode;
using uavsim::sensors::PointCloudFrame;
using uavsim::sensors::RaycastScene;

using uavsim::testing::BoxMesh;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A world whose last material has exactly the given LiDAR reflectivity.
WorldGeometry WorldWith(double reflectivity, std::uint32_t* material) {
  WorldGeometry w;
  w.materials.push_back(Material{"test", 0.5, reflectivity, RadarClass::kConcrete});
  *material = static_cast<std::uint32_t>(w.materials.size() - 1);
  return w;
}

// A wall whose face toward the sensor is the plane x = d, over y in [y0, y1], z in [z0, z1].
WorldGeometry Wall(double d, double y0, double y1, double z0, double z1, double reflectivity) {
  std::uint32_t m;
  WorldGeometry w = WorldWith(reflectivity, &m);
  w.meshes.push_back(BoxMesh(Eigen::Vector3f(d, y0, z0), Eigen::Vector3f(d + 1.0, y1, z1), m));
  return w;
}

// Noise-free, dropout-free, clear-air spinning LiDAR at the origin, looking along +x.
LidarConfig QuietSpinning() {
  LidarConfig c;
  c.range_noise_m = 0.0;
  c.dropout = 0.0;
  c.azimuth_resolution_deg = 1.0;
  c.channels = 32;
  c.vertical_min_deg = -15.0;
  c.vertical_max_deg = 45.0;
  c.max_range_m = 200.0;
  c.min_range_m = 0.5;
  c.full_overlap_range_m = 2.0;
  return c;
}

double Range(const LidarPoint& p, const Eigen::Vector3d& o = Eigen::Vector3d::Zero()) {
  return (Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - o).norm();
}

// Root of a continuous f with f(lo), f(hi) of opposite signs.
double Bisect(const std::function<double(double)>& f, double lo, double hi) {
  const bool lo_negative = f(lo) < 0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((f(mid) < 0) == lo_negative ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Entry distance of the ray o + t d into the box [lo, hi] (slab method), or -1.
double SlabEntry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
                 const Eigen::Vector3d& hi) {
  double t0 = 0.0, t1 = 1e30;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (o[k] < lo[k] || o[k] > hi[k]) return -1.0;
      continue;
    }
    double a = (lo[k] - o[k]) / d[k], b = (hi[k] - o[k]) / d[k];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return t0 <= t1 ? t0 : -1.0;
}

PointCloudFrame CaptureOnce(const LidarConfig& c, const WorldGeometry& w,
                            const WeatherConfig& weather = {}, std::uint64_t seed = 1) {
  RaycastScene scene(w);
  Lidar lidar(c, scene);
  RngStream noise(seed, "lidar");
  return lidar.Capture(0.0, weather, noise);
}

// Whether the az = 0 beam of a one-channel horizontal LiDAR returns from a
// head-on wall at distance d (the wall's face sits at x = d).
bool DetectsWallAt(double d, double reflectivity, const LidarConfig& c,
                   const WeatherConfig& weather) {
  const PointCloudFrame f = CaptureOnce(c, Wall(d, -1e3, 1e3, -1e3, 1e3, reflectivity), weather);
  for (const LidarPoint& p : f.points)
    if (p.t_offset_s == 0.0f && std::abs(p.x_m - d) < 0.5) return true;
  return false;
}

LidarConfig OneHorizontalChannel() {
  LidarConfig c = QuietSpinning();
  c.channels = 1;
  c.vertical_min_deg = -1.0;  // one channel sits at the mean: 0 deg
  c.vertical_max_deg = 1.0;
  c.azimuth_resolution_deg = 5.0;
  c.return_mode = LidarReturnMode::kLast;  // the wall's echo, not the fog's in front of it
  return c;
}

// Largest wall distance at which the head-on beam still returns (bisection).
double MeasuredMaxRange(double reflectivity, const LidarConfig& c, const WeatherConfig& weather,
                        double hi) {
  double lo = 5.0;
  REQUIRE(DetectsWallAt(lo, reflectivity, c, weather));
  REQUIRE_FALSE(DetectsWallAt(hi, reflectivity, c, weather));
  while (hi - lo > 0.01) {
    const double mid = 0.5 * (lo + hi);
    (DetectsWallAt(mid, reflectivity, c, weather) ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

TEST_CASE("Lidar: ranges to a plane are d / cos(angle to its normal)", "[sensors]") {
  const double d = 20.0;
  const WorldGeometry wall = Wall(d, -30, 30, -15, 15, 0.5);
  SECTION("without noise: exact to float precision") {
    const PointCloudFrame f = CaptureOnce(QuietSpinning(), wall);
    REQUIRE(f.points.size() > 1000);
    for (const LidarPoint& p : f.points) {
      const double r = Range(p);
      const double cos_to_normal = p.x_m / r;  // the wall's normal is -x
      CHECK(std::abs(r - d / cos_to_normal) < 1e-3);
      CHECK(std::abs(p.x_m - d) < 1e-3);
    }
    CHECK(f.spurious == 0);
  }
  SECTION("with noise sigma: zero mean, std sigma, 3-sigma tail as a normal's") {
    LidarConfig c = QuietSpinning();
    c.range_noise_m = 0.05;
    c.azimuth_resolution_deg = 0.2;
    const PointCloudFrame f = CaptureOnce(c, wall);
    const auto n = static_cast<double>(f.points.size());
    REQUIRE(n > 10000);
    double sum = 0, sum2 = 0, beyond3 = 0, worst = 0;
    for (const LidarPoint& p : f.points) {
      // The noise moves the point along its beam, so the beam direction is
      // p / |p| and the true range d / cos.
      const double r = Range(p);
      const double e = r - d / (p.x_m / r);
      sum += e;
      sum2 += e * e;
      beyond3 += std::abs(e) > 3 * c.range_noise_m;
      worst = std::max(worst, std::abs(e));
    }
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    CHECK(std::abs(mean) < 4 * c.range_noise_m / std::sqrt(n));
    CHECK(sd == Approx(c.range_noise_m).epsilon(0.03));
    const double p3 = 0.0027;  // P(|Z| > 3)
    CHECK(beyond3 <= n * p3 + 4 * std::sqrt(n * p3));
    CHECK(worst < 6 * c.range_noise_m);
  }
}

TEST_CASE("Lidar: ranges to a box's faces match the slab-method distance", "[sensors]") {
  std::uint32_t m;
  WorldGeometry w = WorldWith(0.3, &m);
  const Eigen::Vector3d lo(10, -1, -1), hi(12, 1, 1.5);
  w.meshes.push_back(BoxMesh(lo.cast<float>(), hi.cast<float>(), m));
  LidarConfig c = QuietSpinning();
  c.pose.position_m = {0.0, -4.0, 0.2};  // sees the face x = 10 and the face y = -1
  c.azimuth_resolution_deg = 0.1;
  c.range_noise_m = 0.01;
  const PointCloudFrame f = CaptureOnce(c, w);
  const Eigen::Vector3d o = c.pose.position_m;
  int on_front = 0, on_side = 0, beyond3 = 0;
  for (const LidarPoint& p : f.points) {
    const Eigen::Vector3d dir = (Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - o).normalized();
    const double expected = SlabEntry(o, dir, lo, hi);
    REQUIRE(expected > 0);
    const double e = Range(p, o) - expected;
    beyond3 += std::abs(e) > 3 * c.range_noise_m;
    CHECK(std::abs(e) < 6 * c.range_noise_m);
    const Eigen::Vector3d hit = o + expected * dir;
    on_front += std::abs(hit.x() - lo.x()) < 1e-9;
    on_side += std::abs(hit.y() - lo.y()) < 1e-9;
  }
  CHECK(on_front > 50);
  CHECK(on_side > 50);
  const double n = static_cast<double>(f.points.size());
  CHECK(beyond3 <= n * 0.0027 + 4 * std::sqrt(n * 0.0027));
}

TEST_CASE("Lidar: the point count is the beams minus those that miss the plane", "[sensors]") {
  const double d = 10, y0 = -7.31, y1 = 5.13, z0 = -2.23, z1 = 4.71;
  LidarConfig c = QuietSpinning();
  c.azimuth_resolution_deg = 0.7;
  // Beams by the documented pattern: evenly spaced channels, N_az = ceil(360 / res) columns.
  const int n_az = static_cast<int>(std::ceil(360.0 / c.azimuth_resolution_deg));
  std::size_t expected = 0;
  double margin = 1e9;
  for (int ch = 0; ch < c.channels; ++ch) {
    const double el =
        (c.vertical_min_deg + (c.vertical_max_deg - c.vertical_min_deg) * ch / (c.channels - 1)) *
        kPi / 180.0;
    for (int k = 0; k < n_az; ++k) {
      const double az = 2 * kPi * k / n_az;
      const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                std::sin(el));
      if (dir.x() <= 0) continue;
      const double y = d * dir.y() / dir.x(), z = d * dir.z() / dir.x();
      margin = std::min(
          {margin, std::abs(y - y0), std::abs(y - y1), std::abs(z - z0), std::abs(z - z1)});
      expected += y > y0 && y < y1 && z > z0 && z < z1;
    }
  }
  REQUIRE(margin > 1e-3);  // no beam grazes an edge, so float rounding cannot flip one
  const PointCloudFrame f = CaptureOnce(c, Wall(d, y0, y1, z0, z1, 0.5));
  CHECK(f.rays_cast == static_cast<std::size_t>(c.channels * n_az));
  CHECK(f.points.size() == expected);
  CHECK(expected > 300);

  SECTION("dropout p keeps a Binomial(n, 1 - p) share") {
    c.dropout = 0.25;
    const PointCloudFrame g = CaptureOnce(c, Wall(d, y0, y1, z0, z1, 0.5));
    const double n = static_cast<double>(expected), kept = 1.0 - c.dropout;
    CHECK(std::abs(static_cast<double>(g.points.size()) - n * kept) <=
          4 * std::sqrt(n * kept * c.dropout));
    CHECK(g.points.size() < expected);
  }
}

TEST_CASE("Lidar: extinction at 905 nm follows Kim et al. and Marshall-Palmer", "[sensors]") {
  // Kim et al. 2001: alpha = 3.912 / V (lambda / 550 nm)^-q; q = 0 below 500 m,
  // q = V - 0.5 (V in km) up to 1 km, 0.16 V + 0.34 up to 6 km.
  CHECK(uavsim::sensors::FogExtinctionPerM(200) == Approx(3.912 / 200));
  CHECK(uavsim::sensors::FogExtinctionPerM(800) ==
        Approx(3.912 / 800 * std::pow(905.0 / 550.0, -0.3)));
  CHECK(uavsim::sensors::FogExtinctionPerM(3000) ==
        Approx(3.912 / 3000 * std::pow(905.0 / 550.0, -(0.16 * 3 + 0.34))));
  // Rain: extinction efficiency 2 integrated numerically over Marshall-Palmer drops.
  for (double rain : {1.0, 10.0, 50.0}) {
    const double lambda = 4.1 * std::pow(rain, -0.21);
    double alpha = 0;
    const double dd = 1e-3;  // mm
    for (double dia = 0.5 * dd; dia < 20; dia += dd)
      alpha += 2 * (kPi / 4) * dia * dia * 1e-6 * 8000 * std::exp(-lambda * dia) * dd;
    CHECK(uavsim::sensors::RainExtinctionPerM(rain) == Approx(alpha).epsilon(1e-4));
  }
  CHECK(uavsim::sensors::RainExtinctionPerM(0) == 0);
}

TEST_CASE("Lidar: fog and rain shorten the detection range as Beer-Lambert predicts", "[sensors]") {
  const LidarConfig c = OneHorizontalChannel();
  const double rho = 0.5;
  const double p_th = c.reference_reflectivity / (c.max_range_m * c.max_range_m);
  // rho exp(-2 alpha R) / R^2 = P_th, solved for R.
  auto analytic = [&](double alpha) {
    return Bisect(
        [&](double r) { return std::log(rho) - 2 * alpha * r - 2 * std::log(r) - std::log(p_th); },
        1.0, 1e4);
  };
  const double clear = MeasuredMaxRange(rho, c, {}, 600);
  CHECK(clear == Approx(c.max_range_m * std::sqrt(rho / c.reference_reflectivity)).margin(0.05));
  WeatherConfig fog;
  fog.fog_visibility_m = 200.0;  // below 500 m: alpha = 3.912 / V at any wavelength
  const double r_fog = MeasuredMaxRange(rho, c, fog, 600);
  CHECK(r_fog == Approx(analytic(3.912 / 200.0)).margin(0.05));
  CHECK(r_fog < 0.3 * clear);
  WeatherConfig rain;
  rain.rain_mm_h = 50.0;
  const double lambda = 4.1 * std::pow(50.0, -0.21);
  const double r_rain = MeasuredMaxRange(rho, c, rain, 600);
  CHECK(r_rain == Approx(analytic(kPi * 8000 / std::pow(lambda, 3) * 1e-6)).margin(0.05));
  CHECK(r_rain < clear);
}

TEST_CASE("Lidar: backscatter echoes appear only in weather, near the sensor", "[sensors]") {
  std::uint32_t m;
  WorldGeometry w = WorldWith(0.2, &m);
  w.meshes.push_back(BoxMesh({-300, -300, -2}, {300, 300, -1.5}, m));  // ground at z = -1.5
  LidarConfig c = QuietSpinning();
  c.min_range_m = 1.0;
  c.full_overlap_range_m = 10.0;
  // Off-ground points are the spurious ones: count them by geometry.
  auto off_ground = [](const PointCloudFrame& f) {
    std::size_t n = 0;
    for (const LidarPoint& p : f.points) n += std::abs(p.z_m + 1.5f) > 1e-3f;
    return n;
  };
  const PointCloudFrame clear = CaptureOnce(c, w);
  CHECK(clear.spurious == 0);
  CHECK(off_ground(clear) == 0);
  CHECK(clear.points.size() > 1000);

  WeatherConfig fog;
  fog.fog_visibility_m = 50.0;
  const PointCloudFrame foggy = CaptureOnce(c, w, fog);
  CHECK(foggy.spurious == off_ground(foggy));
  CHECK(foggy.spurious > foggy.rays_cast / 4);  // most sky beams in 50 m fog
  std::vector<double> ranges;
  for (const LidarPoint& p : foggy.points)
    if (std::abs(p.z_m + 1.5f) > 1e-3f) ranges.push_back(Range(p));
  std::sort(ranges.begin(), ranges.end());
  CHECK(ranges.front() >= c.min_range_m);
  CHECK(ranges.back() < 30.0);
  CHECK(ranges[ranges.size() / 2] < c.full_overlap_range_m);

  // Light haze: at 2 km the mean echo peaks at ~0.6 P_th (at 2 m, where the
  // overlap ramp meets 1/r^2), and a fade summing ~6900 speckle cells
  // (lidar.h) never reaches the 1.7 times its mean that would take.
  WeatherConfig light_fog;
  light_fog.fog_visibility_m = 2000.0;
  CHECK(CaptureOnce(c, w, light_fog).spurious == 0);

  WeatherConfig rain;
  rain.rain_mm_h = 50.0;
  const PointCloudFrame rainy = CaptureOnce(c, w, rain);
  CHECK(rainy.spurious == off_ground(rainy));
  CHECK(rainy.spurious > 0);
  for (const LidarPoint& p : rainy.points)
    if (std::abs(p.z_m + 1.5f) > 1e-3f) CHECK(Range(p) < 20.0);
}

TEST_CASE("Lidar: intensity is rho cos(i) Rs^2 / R^2: it falls as 1/R^2", "[sensors]") {
  const double rho = 0.3;
  LidarConfig c = QuietSpinning();
  c.saturation_range_m = 5.0;
  std::vector<float> head_on;
  for (double d : {20.0, 40.0}) {
    const PointCloudFrame f = CaptureOnce(c, Wall(d, -50, 50, -30, 30, rho));
    REQUIRE(f.points.size() > 100);
    for (const LidarPoint& p : f.points) {
      const double r = Range(p), cos_i = p.x_m / r;
      const double expected = std::min(1.0, rho * cos_i * 25.0 / (r * r));
      CHECK(p.intensity == Approx(expected).epsilon(1e-4));
      CHECK(p.intensity > 0.0f);
      CHECK(p.intensity <= 1.0f);
    }
    // The first column's beam nearest the horizon: the same beam at both distances.
    const LidarPoint* best = nullptr;
    for (const LidarPoint& p : f.points)
      if (p.t_offset_s == 0.0f && (!best || std::abs(p.z_m) < std::abs(best->z_m))) best = &p;
    REQUIRE(best);
    head_on.push_back(best->intensity);
  }
  CHECK(head_on[0] / head_on[1] == Approx(4.0).epsilon(1e-3));
}

TEST_CASE("Lidar: a target moving sideways is smeared by v times the sweep time", "[sensors]") {
  // One horizontal channel turning once a second: the beam sweeps +y across a
  // box at x = 10 that moves +y at v, so the beam catches its trailing edge
  // at t1 and its leading edge at t2 with 10 tan(2 pi t) = edge(t).
  const double v = 20.0, w = 2.0, y0 = 3.0, d = 10.0;
  LidarConfig c = OneHorizontalChannel();
  c.return_mode = LidarReturnMode::kStrongest;
  c.timing.rate_hz = 1.0;
  c.azimuth_resolution_deg = 0.05;
  c.time_slices_per_frame = 4000;
  auto extent = [&](double speed, double* worst_offset) {
    std::uint32_t m;
    WorldGeometry world = WorldWith(0.4, &m);
    RaycastScene scene(world);
    scene.AddMovingObject(BoxMesh({-0.5f, -1.0f, -1.0f}, {0.5f, 1.0f, 1.0f}, m), [=](double t) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.translation() = Eigen::Vector3d(d + 0.5, y0 + speed * t, 0.0);
      return X;
    });
    Lidar lidar(c, scene);
    RngStream noise(1, "lidar");
    const PointCloudFrame f = lidar.Capture(0.0, {}, noise);
    double lo = 1e9, hi = -1e9;
    *worst_offset = 0;
    for (const LidarPoint& p : f.points) {
      if (std::abs(p.x_m - d) > 1e-3) continue;  // the front face only
      lo = std::min(lo, static_cast<double>(p.y_m));
      hi = std::max(hi, static_cast<double>(p.y_m));
      // Each point lies on the box where the box was at that point's time.
      const double centre = y0 + speed * p.t_offset_s;
      *worst_offset = std::max(*worst_offset, std::abs(p.y_m - centre) - w / 2);
    }
    return hi - lo;
  };
  auto crossing = [&](double edge) {
    return Bisect([&](double t) { return d * std::tan(2 * kPi * t) - (edge + v * t); }, 0.0, 0.2);
  };
  const double t1 = crossing(y0 - w / 2), t2 = crossing(y0 + w / 2);
  const double tolerance = 4 * d * c.azimuth_resolution_deg * kPi / 180 + v / 4000.0;
  double offset = 0;
  const double still = extent(0.0, &offset);
  CHECK(still == Approx(w).margin(tolerance));
  const double moving = extent(v, &offset);
  CHECK(moving == Approx(w + v * (t2 - t1)).margin(tolerance));
  CHECK(moving - still > 0.5);
  CHECK(offset < tolerance);
}

TEST_CASE("Lidar: one seed gives one cloud, whatever the number of threads", "[sensors]") {
  std::uint32_t m;
  WorldGeometry w = WorldWith(0.3, &m);
  w.meshes.push_back(BoxMesh({-100, -100, -2}, {100, 100, -1.5}, m));
  w.meshes.push_back(BoxMesh({15, -5, -1.5}, {16, 5, 6}, m));
  LidarConfig c = QuietSpinning();
  c.range_noise_m = 0.03;
  c.dropout = 0.1;
  c.full_overlap_range_m = 10.0;
  WeatherConfig weather;
  weather.fog_visibility_m = 300.0;
  weather.rain_mm_h = 20.0;
  auto capture = [&](std::uint64_t seed, int threads) {
    RaycastScene scene(w);
    scene.AddMovingObject(BoxMesh({-0.3f, -0.3f, -0.1f}, {0.3f, 0.3f, 0.1f}, m), [](double t) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.translation() = Eigen::Vector3d(8.0, -3.0 + 15.0 * t, 3.0);
      return X;
    });
    Lidar lidar(c, scene);
    RngStream noise(seed, "lidar1");
    tbb::task_arena arena(threads);
    std::vector<PointCloudFrame> frames;
    arena.execute([&] {
      for (int k = 0; k < 2; ++k) frames.push_back(lidar.Capture(0.1 * k, weather, noise));
    });
    return frames;
  };
  auto same = [](const std::vector<PointCloudFrame>& a, const std::vector<PointCloudFrame>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (a[k].points.size() != b[k].points.size() || a[k].spurious != b[k].spurious) return false;
      if (std::memcmp(a[k].points.data(), b[k].points.data(),
                      a[k].points.size() * sizeof(LidarPoint)) != 0)
        return false;
    }
    return true;
  };
  const auto one = capture(7, 1);
  CHECK(same(one, capture(7, 1)));
  CHECK(same(one, capture(7, 2)));
  CHECK_FALSE(same(one, capture(8, 2)));
  CHECK(one[0].spurious > 0);
}

TEST_CASE("Lidar: explicit vertical angles set the channels' elevations", "[sensors]") {
  LidarConfig c = QuietSpinning();
  c.channels = 3;
  c.vertical_angles_deg = {-10.0, 2.5, 25.0};
  WorldGeometry w;
  RaycastScene scene(w);
  Lidar lidar(c, scene);
  const auto beams = lidar.Beams(0.0);
  REQUIRE(beams.size() == 3 * 360);
  for (std::size_t i = 0; i < beams.size(); ++i) {
    const double el = std::asin(beams[i].ray.direction.z()) * 180 / kPi;
    CHECK(el == Approx(c.vertical_angles_deg[i % 3]).margin(1e-4));
    CHECK(beams[i].t_offset_s == Approx((i / 3) * 0.1 / 360).margin(1e-7));
  }
}

TEST_CASE("Lidar: the rosette stays in its field of view and fills it over time", "[sensors]") {
  LidarConfig c = QuietSpinning();
  c.preset = LidarPreset::kLivoxRosette;
  c.points_per_s = 100000;
  c.fov_deg = 70;
  c.pose.rpy_deg = {0.0, 0.0, 30.0};  // yawed: the axis is the sensor's x in the world
  WorldGeometry w;
  RaycastScene scene(w);
  Lidar lidar(c, scene);
  const Eigen::Vector3f axis(std::cos(kPi / 6), std::sin(kPi / 6), 0);
  // Occupied 1 x 1 deg cells of the field of view after one and after ten frames.
  std::set<std::pair<int, int>> cells;
  std::size_t after_one = 0;
  for (int k = 0; k < 10; ++k) {
    const auto beams = lidar.Beams(0.1 * k);
    REQUIRE(beams.size() == 10000);
    for (const auto& b : beams) {
      const Eigen::Vector3f& dir = b.ray.direction;
      const double off_axis_deg = std::acos(std::min(1.0f, dir.dot(axis))) * 180 / kPi;
      CHECK(off_axis_deg <= 35.0 + 1e-3);
      const Eigen::Vector3f left(-std::sin(kPi / 6), std::cos(kPi / 6), 0);
      const double u = std::atan2(dir.dot(left), dir.dot(axis)) * 180 / kPi;
      const double v = std::asin(dir.z()) * 180 / kPi;
      cells.insert({static_cast<int>(std::floor(u)), static_cast<int>(std::floor(v))});
    }
    if (k == 0) after_one = cells.size();
  }
  const double fov_cells = kPi * 35 * 35;
  CHECK(after_one < 0.8 * fov_cells);
  CHECK(cells.size() > 1.15 * after_one);
  CHECK(cells.size() > 0.9 * fov_cells);
  // Against a wall, the returns keep their beams' times and lie in the cone.
  const PointCloudFrame f = CaptureOnce(c, Wall(30, -100, 100, -100, 100, 0.5));
  CHECK(f.points.size() > 9000);
  for (const LidarPoint& p : f.points) {
    const Eigen::Vector3f dir = Eigen::Vector3f(p.x_m, p.y_m, p.z_m).normalized();
    CHECK(std::acos(std::min(1.0f, dir.dot(axis))) * 180 / kPi <= 35.0 + 1e-3);
    CHECK(p.t_offset_s >= 0.0f);
    CHECK(p.t_offset_s < 0.1f);
  }
}

TEST_CASE("Lidar: the Mid-360 scan covers 360 x 59 deg (-7 to +52) at points_per_s", "[sensors]") {
  LidarConfig c = QuietSpinning();
  c.preset = LidarPreset::kLivoxMid360;
  c.points_per_s = 200000;
  c.pose.rpy_deg = {0.0, 0.0, 30.0};  // a yaw turns the azimuths only
  WorldGeometry w;
  RaycastScene scene(w);
  Lidar lidar(c, scene);
  // Point rate: ceil(points_per_s / rate_hz) beams a frame, beam i at i / points_per_s.
  CHECK(c.RaysPerFrame() == 20000.0);
  const auto beams = lidar.Beams(3.7);
  REQUIRE(beams.size() == 20000);
  double el_min = 90, el_max = -90;
  // Occupied 10 deg (azimuth) x 5 deg (elevation) cells of the field in one frame.
  std::set<std::pair<int, int>> cells;
  for (std::size_t i = 0; i < beams.size(); ++i) {
    CHECK(beams[i].t_offset_s == Approx(i / 200000.0).margin(1e-7));
    const Eigen::Vector3f& d = beams[i].ray.direction;
    CHECK(d.norm() == Approx(1.0).margin(1e-5));
    const double el = std::asin(std::clamp(d.z(), -1.0f, 1.0f)) * 180 / kPi;
    const double az = std::atan2(d.y(), d.x()) * 180 / kPi + 180.0;  // [0, 360]
    el_min = std::min(el_min, el);
    el_max = std::max(el_max, el);
    cells.insert({static_cast<int>(az / 10.0) % 36, static_cast<int>((el + 7.0) / 5.0)});
  }
  CHECK(el_min >= -7.0 - 1e-3);
  CHECK(el_max <= 52.0 + 1e-3);
  CHECK(el_min < -6.5);  // the whole field is swept, not a band of it
  CHECK(el_max > 51.5);
  // 36 azimuth sectors x 12 elevation bands (the last one 4 deg tall): every one hit.
  CHECK(cells.size() == 36 * 12);
  // Non-repetitive: the next frame's beams are not this frame's.
  const auto next = lidar.Beams(3.8);
  int same = 0;
  for (std::size_t i = 0; i < beams.size(); ++i)
    same += (next[i].ray.direction - beams[i].ray.direction).norm() < 1e-3f;
  CHECK(same < 200);
  // Upright at h above a ground plane of reflectivity rho, a beam at
  // elevation el < 0 meets it at R = h / sin(-el) with cos(i) = sin(-el) and
  // is detected iff rho sin(-el) / R^2 >= reference_reflectivity /
  // max_range_m^2 (lidar.h): count those beams from their directions alone.
  const double h = 2.0, rho = 0.5;
  c.pose.position_m = {0.0, 0.0, h};
  c.pose.rpy_deg = {0.0, 0.0, 0.0};
  std::uint32_t m;
  WorldGeometry ground = WorldWith(rho, &m);
  ground.meshes.push_back(
      BoxMesh(Eigen::Vector3f(-500, -500, -1), Eigen::Vector3f(500, 500, 0), m));
  Lidar upright(c, scene);
  int expected = 0, below = 0, marginal = 0;
  const double p_th = c.reference_reflectivity / (c.max_range_m * c.max_range_m);
  for (const auto& b : upright.Beams(0.0)) {
    const double s_el = -static_cast<double>(b.ray.direction.z());
    if (s_el <= 0) continue;
    ++below;
    const double r = h / s_el, p = rho * s_el / (r * r);
    expected += p >= p_th;
    marginal += std::abs(p / p_th - 1.0) < 1e-4;
  }
  // 7 / 59 of the beams point below the horizon (uniform in elevation); of
  // those, the ones steeper than asin((P_th h^2 / rho)^(1/3)) = 1.55 deg are
  // detected.
  CHECK(static_cast<double>(below) / 20000.0 == Approx(7.0 / 59.0).margin(0.005));
  const double cut_deg = std::asin(std::cbrt(p_th * h * h / rho)) * 180 / kPi;
  CHECK(static_cast<double>(expected) / below == Approx((7.0 - cut_deg) / 7.0).margin(0.02));
  const PointCloudFrame f = CaptureOnce(c, ground);
  CHECK(std::abs(static_cast<int>(f.points.size()) - expected) <= marginal);
  for (const LidarPoint& p : f.points) CHECK(std::abs(p.z_m) < 1e-3);
}

TEST_CASE("LidarConfig: rules name the field, the value and the rule", "[sensors]") {
  auto error_of = [](const std::string& text) {
    LidarConfig c;
    try {
      uavsim::core::FromJson(uavsim::core::Json::parse(text), "l.json", "/nodes/1/sensor", c);
    } catch (const uavsim::core::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error_of(R"({"channels": 4, "vertical_angles_deg": [1, 2, 3]})") ==
        "l.json: /nodes/1/sensor/vertical_angles_deg: vertical_angles_deg has 3 angles but "
        "channels is 4 (give one angle per channel, or none)");
  CHECK(error_of(R"({"min_range_m": 3, "full_overlap_range_m": 2})") ==
        "l.json: /nodes/1/sensor/full_overlap_range_m: full_overlap_range_m must be at least "
        "min_range_m (3 m)");
  CHECK_THAT(error_of(R"({"reference_reflectivity": 0})"),
             Catch::StartsWith("l.json: /nodes/1/sensor/reference_reflectivity: expected"));
  CHECK_THAT(error_of(R"({"return_mode": "first"})"), Catch::Contains("\"strongest\", \"last\""));
  CHECK(error_of(R"({"channels": 3, "vertical_angles_deg": [1, 2, 3], "return_mode": "last"})")
            .empty());
  LidarConfig bad;
  bad.vertical_angles_deg = {1.0};
  WorldGeometry w;
  RaycastScene scene(w);
  CHECK_THROWS_WITH(Lidar(bad, scene),
                    "LidarConfig: vertical_angles_deg must have one angle per channel");
}

TEST_CASE("EncodePly: a PLY header by the spec, then little-endian float vertices", "[sensors]") {
  PointCloudFrame f;
  f.t_start_s = 12.5;
  f.points.push_back({1.5f, -2.25f, 3.0f, 0.75f, 0.0125f});
  f.points.push_back({4.0f, 5.0f, 6.0f, 0.5f, 0.05f});
  const std::string ply = uavsim::sensors::EncodePly(f);
  const std::string end = "end_header\n";
  const std::size_t body = ply.find(end);
  REQUIRE(body != std::string::npos);
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at < body + end.size()) {
    const std::size_t nl = ply.find('\n', at);
    lines.push_back(ply.substr(at, nl - at));
    at = nl + 1;
  }
  REQUIRE(lines.size() >= 9);
  CHECK(lines[0] == "ply");
  CHECK(lines[1] == "format binary_little_endian 1.0");
  std::vector<std::string> declarations;
  for (const std::string& l : lines)
    if (l.rfind("comment", 0) != 0 && l != "ply" && l.rfind("format", 0) != 0)
      declarations.push_back(l);
  CHECK(declarations == std::vector<std::string>{"element vertex 2", "property float x",
                                                 "property float y", "property float z",
                                                 "property float intensity", "property float t",
                                                 "end_header"});
  CHECK(std::find(lines.begin(), lines.end(), "comment t_start_s 12.5") != lines.end());
  const std::size_t data = body + end.size();
  REQUIRE(ply.size() == data + 2 * 5 * 4);
  float first[5];
  for (int k = 0; k < 5; ++k) {
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b)
      bits |= static_cast<std::uint32_t>(static_cast<unsigned char>(ply[data + 4 * k + b]))
              << (8 * b);
    std::memcpy(&first[k], &bits, 4);
  }
  CHECK(first[0] == 1.5f);
  CHECK(first[1] == -2.25f);
  CHECK(first[2] == 3.0f);
  CHECK(first[3] == 0.75f);
  CHECK(first[4] == 0.0125f);
}
