// The LiDAR's fog echo against closed forms: the number of speckle cells
// (D theta / lambda)^2, the Gamma(M, 1/M) fade's moments and survival
// function (Erlang for integer M), the detection probability of an echo whose
// mean peaks at half the threshold, and the visibility below which every sky
// beam returns fog. Expected values are computed here, never taken from the
// model's own output.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/json_io.h"
#include "sensors/lidar.h"
#include "sensors/lidar_atmosphere.h"

using uavsim::core::Mix64;
using uavsim::core::RngStream;
using uavsim::core::WeatherConfig;
using uavsim::core::WorldGeometry;
using uavsim::sensors::FogExtinctionPerM;
using uavsim::sensors::FogSpeckleCells;
using uavsim::sensors::FogSpeckleFade;
using uavsim::sensors::Lidar;
using uavsim::sensors::LidarConfig;
using uavsim::sensors::RaycastScene;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kC = 299792458.0;

// Gamma(M, 1/M) survival P(X > x) for integer M (Erlang):
// e^{-M x} sum_{k < M} (M x)^k / k!.
double ErlangSurvival(int m, double x) {
  double term = 1.0, sum = 1.0;
  for (int k = 1; k < m; ++k) {
    term *= m * x / k;
    sum += term;
  }
  return std::exp(-m * x) * sum;
}

// Fades of n beams, each from its own stream as Lidar::Capture derives them.
std::vector<double> Fades(double cells, std::size_t n) {
  std::vector<double> f(n);
  const std::uint64_t key = 0x5eedf06ULL;
  for (std::size_t i = 0; i < n; ++i) {
    RngStream rng(Mix64(key ^ Mix64(i)));
    f[i] = FogSpeckleFade(cells, rng);
  }
  return f;
}

// 32 channels over [-15, 45] deg, 1 deg of azimuth: 11 520 beams, no noise.
LidarConfig SkyLidar() {
  LidarConfig c;
  c.range_noise_m = 0.0;
  c.dropout = 0.0;
  c.azimuth_resolution_deg = 1.0;
  c.min_range_m = 1.0;
  c.full_overlap_range_m = 10.0;
  return c;
}

// Peak over r of the mean fog echo rho_v xi(r) e^{-2 alpha r} / r^2 with the
// linear overlap from r1 to r2 (lidar.h): on the ramp, d/dr ln = 0 gives
// 2 alpha r^2 + (1 - 2 alpha r1) r - 2 r1 = 0; past r2 the echo only falls.
double PeakFogEcho(const LidarConfig& c, double visibility_m) {
  const double alpha = FogExtinctionPerM(visibility_m);
  const double rho_v = kPi * (0.046 / visibility_m) * kC * c.pulse_width_ns * 1e-9 / 2.0;
  const double r1 = c.min_range_m, r2 = c.full_overlap_range_m;
  const double b = 1.0 - 2.0 * alpha * r1;
  const double r = std::min(r2, (-b + std::sqrt(b * b + 16.0 * alpha * r1)) / (4.0 * alpha));
  return rho_v * (r - r1) / (r2 - r1) * std::exp(-2.0 * alpha * r) / (r * r);
}

std::size_t SpuriousInEmptyWorld(const LidarConfig& c, double visibility_m) {
  WorldGeometry w;
  RaycastScene scene(w);
  Lidar lidar(c, scene);
  WeatherConfig fog;
  fog.fog_visibility_m = visibility_m;
  RngStream noise(3, "lidar");
  const auto frame = lidar.Capture(0.0, fog, noise);
  REQUIRE(frame.points.size() == frame.spurious);
  return frame.spurious;
}

}  // namespace

TEST_CASE("FogSpeckleCells: (D theta / lambda)^2 cells, at least one", "[sensors]") {
  LidarConfig c;
  const double n = 25e-3 * 3e-3 / 905e-9;
  CHECK(FogSpeckleCells(c) == Approx(n * n).epsilon(1e-12));
  CHECK(FogSpeckleCells(c) > 6800.0);
  c.receiver_aperture_mm = 0.1;  // D theta < lambda: a single cell
  CHECK(FogSpeckleCells(c) == 1.0);
}

TEST_CASE("FogSpeckleFade: Gamma(M, 1/M) moments and survival over many beams", "[sensors]") {
  const std::size_t n = 200000;
  for (double m : {1.0, 4.0, 2.5, FogSpeckleCells(LidarConfig{})}) {
    INFO("M = " << m);
    const std::vector<double> f = Fades(m, n);
    double sum = 0.0;
    for (double x : f) sum += x;
    const double mean = sum / n;
    double ss = 0.0;
    for (double x : f) ss += (x - mean) * (x - mean);
    const double var = ss / (n - 1);
    // Standard errors: sqrt(1 / (M n)) for the mean; the sample variance's,
    // from Gamma's excess kurtosis 6 / M, (1 / M) sqrt((2 + 6 / M) / n).
    CHECK(std::abs(mean - 1.0) < 5.0 * std::sqrt(1.0 / (m * n)));
    CHECK(std::abs(var - 1.0 / m) < 5.0 / m * std::sqrt((2.0 + 6.0 / m) / n));
    CHECK(*std::min_element(f.begin(), f.end()) > 0.0);
  }
  for (int m : {1, 4}) {
    const std::vector<double> f = Fades(m, n);
    for (double x : {0.25, 0.5, 1.0, 2.0, 3.0}) {
      INFO("M = " << m << ", x = " << x);
      std::size_t above = 0;
      for (double v : f) above += v > x;
      const double p = ErlangSurvival(m, x);
      CHECK(std::abs(static_cast<double>(above) / n - p) <
            5.0 * std::sqrt(p * (1.0 - p) / n) + 1e-6);
    }
  }
}

TEST_CASE("Lidar: a fog echo peaking at P_th / 2 is detected with P(Gamma(M, 1/M) >= 2)",
          "[sensors]") {
  // Visibility 2 km; max_range_m set so that P_th = 2 max_r S(r).
  const double v_m = 2000.0;
  LidarConfig c = SkyLidar();
  c.max_range_m = std::sqrt(c.reference_reflectivity / (2.0 * PeakFogEcho(c, v_m)));
  REQUIRE(c.max_range_m > c.full_overlap_range_m);
  const double beams = 32.0 * 360.0;

  SECTION("one speckle cell (an aperture below lambda / theta): e^-2 of the beams") {
    c.receiver_aperture_mm = 0.1;
    REQUIRE(FogSpeckleCells(c) == 1.0);
    const double p = ErlangSurvival(1, 2.0);
    const double n = static_cast<double>(SpuriousInEmptyWorld(c, v_m));
    CHECK(std::abs(n - beams * p) < 5.0 * std::sqrt(beams * p * (1.0 - p)));
  }
  SECTION("four cells: Erlang's survival") {
    c.receiver_aperture_mm = 2.0 * 905e-9 / (c.beam_divergence_mrad * 1e-3) * 1e3;
    REQUIRE(FogSpeckleCells(c) == Approx(4.0).epsilon(1e-9));
    const double p = ErlangSurvival(4, 2.0);  // 0.042
    const double n = static_cast<double>(SpuriousInEmptyWorld(c, v_m));
    CHECK(std::abs(n - beams * p) < 5.0 * std::sqrt(beams * p * (1.0 - p)));
  }
  SECTION("the default 25 mm aperture: M ~ 6900, none") {
    // Chernoff: P(X >= 2) <= exp(-M (2 - 1 - ln 2)) ~ e^-2100 a beam.
    CHECK(SpuriousInEmptyWorld(c, v_m) == 0);
  }
}

TEST_CASE(
    "Lidar: every sky beam returns fog below the visibility where the mean echo "
    "reaches P_th, none above",
    "[sensors]") {
  const LidarConfig c = SkyLidar();
  const double p_th = c.reference_reflectivity / (c.max_range_m * c.max_range_m);
  // V_crit: max_r S(r) = P_th; S's peak falls with V (bisection on log V).
  double lo = 10.0, hi = 1e5;
  for (int i = 0; i < 200; ++i) {
    const double mid = std::sqrt(lo * hi);
    (PeakFogEcho(c, mid) > p_th ? lo : hi) = mid;
  }
  const double v_crit = lo;
  CHECK(v_crit == Approx(1200.0).margin(100.0));  // ~ 0.108 / (36 P_th) without extinction
  // 10 % either side: the fade must reach 0.9 or 1.1, e^-30 a beam at M ~ 6900.
  CHECK(SpuriousInEmptyWorld(c, 0.9 * v_crit) == 32 * 360);
  CHECK(SpuriousInEmptyWorld(c, 1.1 * v_crit) == 0);
}

TEST_CASE("LidarConfig: receiver_aperture_mm must be positive", "[sensors]") {
  LidarConfig c;
  try {
    uavsim::core::FromJson(uavsim::core::Json::parse(R"({"receiver_aperture_mm": 0})"), "l.json",
                           "/nodes/1/sensor", c);
    FAIL("no error");
  } catch (const uavsim::core::ConfigError& e) {
    CHECK_THAT(std::string(e.what()),
               Catch::StartsWith("l.json: /nodes/1/sensor/receiver_aperture_mm: expected"));
  }
  LidarConfig bad;
  bad.receiver_aperture_mm = -1.0;
  WorldGeometry w;
  RaycastScene scene(w);
  CHECK_THROWS_WITH(Lidar(bad, scene), "LidarConfig: receiver_aperture_mm must be positive");
}
