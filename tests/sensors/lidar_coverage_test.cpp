// The survey's two sensor-side pieces: Lidar::CaptureStatic against a
// capture of the same world with nothing moving, and FramesToCover against
// the cone's solid angle and a brute-force nearest-beam check.
#include "sensors/lidar_coverage.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <vector>

#include "core/rng.h"
#include "sensors/lidar.h"
#include "test_support.h"

namespace uavsim::sensors {
namespace {

constexpr double kPi = 3.14159265358979323846;

core::WorldGeometry WallWorld() {
  core::WorldGeometry w;
  w.materials.push_back(core::Material{"test", 0.5, 0.4, core::RadarClass::kConcrete});
  const auto m = static_cast<std::uint32_t>(w.materials.size() - 1);
  w.meshes.push_back(testing::BoxMesh({30.0f, -50.0f, -20.0f}, {31.0f, 50.0f, 20.0f}, m));
  return w;
}

LidarConfig Rosette(double points_per_s) {
  LidarConfig c;
  c.preset = LidarPreset::kLivoxRosette;
  c.points_per_s = points_per_s;
  c.fov_deg = 70.0;
  return c;
}

TEST_CASE("Lidar::CaptureStatic: the static world alone, as if nothing moved", "[sensors]") {
  const core::WorldGeometry w = WallWorld();
  LidarConfig c = Rosette(50000);
  c.range_noise_m = 0.02;
  core::WeatherConfig rain;
  rain.rain_mm_h = 10.0;
  // With a box flying 10 m in front of the sensor.
  RaycastScene with(w);
  with.AddMovingObject(testing::BoxMesh({-2.0f, -2.0f, -2.0f}, {2.0f, 2.0f, 2.0f}, 1),
                       [](double t) {
                         Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
                         X.translation() = Eigen::Vector3d(10.0, 3.0 * t, 0.0);
                         return X;
                       });
  RaycastScene without(w);
  Lidar a(c, with), b(c, without);
  core::RngStream na(5, "survey"), nb(5, "survey"), nc(5, "survey");
  const PointCloudFrame stat = a.CaptureStatic(-0.1, rain, na);
  const PointCloudFrame alone = b.Capture(-0.1, rain, nb);
  REQUIRE(stat.points.size() == alone.points.size());
  CHECK(std::memcmp(stat.points.data(), alone.points.data(),
                    stat.points.size() * sizeof(LidarPoint)) == 0);
  // The ordinary capture does see the box (returns near x = 8).
  const PointCloudFrame seen = a.Capture(-0.1, rain, nc);
  const auto on_box = [](const PointCloudFrame& f) {
    return std::count_if(f.points.begin(), f.points.end(),
                         [](const LidarPoint& p) { return std::abs(p.x_m - 8.0f) < 0.2f; });
  };
  CHECK(on_box(seen) > 100);
  CHECK(on_box(stat) == 0);
}

TEST_CASE("FramesToCover: a spinning LiDAR covers its field in one turn", "[sensors]") {
  core::WorldGeometry w;
  RaycastScene scene(w);
  LidarConfig c;  // spinning32
  const Lidar lidar(c, scene);
  const LidarCoverage cover = FramesToCover(lidar, 0.5 / 200.0, 0.999, 5.0);
  CHECK(cover.frames == 1);
  CHECK(cover.covered_cells == cover.field_cells);
  CHECK(cover.field_cells > 1000);
}

TEST_CASE("FramesToCover: a rosette's field is its cone, covered to the fraction asked",
          "[sensors]") {
  core::WorldGeometry w;
  RaycastScene scene(w);
  const LidarConfig c = Rosette(20000);
  const Lidar lidar(c, scene);
  const double cell = kPi / 180.0;  // 1 deg
  const LidarCoverage cover = FramesToCover(lidar, cell, 0.95, 20.0);
  // The field: a 35 deg half-angle cone, 2 pi (1 - cos 35 deg) sr, in cells
  // of cell^2 sr (boundary cells add a few per cent).
  const double cone_cells = 2.0 * kPi * (1.0 - std::cos(35.0 * kPi / 180.0)) / (cell * cell);
  CHECK(static_cast<double>(cover.field_cells) > 0.97 * cone_cells);
  CHECK(static_cast<double>(cover.field_cells) < 1.15 * cone_cells);
  CHECK(cover.frames > 1);
  CHECK(static_cast<double>(cover.covered_cells) >= 0.95 * static_cast<double>(cover.field_cells));
  // Fewer frames for less coverage, more for more.
  CHECK(FramesToCover(lidar, cell, 0.5, 20.0).frames < cover.frames);
  CHECK(FramesToCover(lidar, cell, 0.995, 20.0).frames > cover.frames);
  // Independently: random directions inside the cone (away from its rim)
  // mostly have a beam of the survey's frames within about one cell.
  std::vector<Eigen::Vector3f> beams;
  for (int k = 1; k <= cover.frames; ++k)
    for (const LidarBeam& b : lidar.Beams(-k * lidar.frame_period_s()))
      beams.push_back(b.ray.direction);
  core::RngStream rng(3, "probe");
  int near = 0;
  const int probes = 300;
  for (int i = 0; i < probes; ++i) {
    const double off = std::acos(1.0 - rng.Uniform() * (1.0 - std::cos(33.0 * kPi / 180.0)));
    const double around = rng.Uniform(0.0, 2.0 * kPi);
    const Eigen::Vector3f d(std::cos(off), std::sin(off) * std::cos(around),
                            std::sin(off) * std::sin(around));
    float best = -1.0f;
    for (const auto& b : beams) best = std::max(best, b.dot(d));
    if (std::acos(std::min(1.0f, best)) <= 1.0 * cell) ++near;
  }
  CHECK(near >= 0.9 * probes);
}

TEST_CASE("FramesToCover: bad arguments are refused", "[sensors]") {
  core::WorldGeometry w;
  RaycastScene scene(w);
  const Lidar lidar(LidarConfig{}, scene);
  CHECK_THROWS_AS(FramesToCover(lidar, 0.0, 0.9, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(FramesToCover(lidar, 0.01, 0.0, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(FramesToCover(lidar, 0.01, 1.5, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(FramesToCover(lidar, 0.01, 0.9, -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::sensors

namespace uavsim::sensors {
namespace {

TEST_CASE("LidarConfig::FieldSolidAngleSr: the solid angle the scan fills over time", "[sensors]") {
  core::WorldGeometry w;
  RaycastScene scene(w);
  const double cell = 1.0 * kPi / 180.0;
  // The cells a long scan reaches, times a cell's solid angle, against the
  // formula (boundary cells add a few per cent).
  LidarConfig mid360;
  mid360.preset = LidarPreset::kLivoxMid360;
  mid360.points_per_s = 50000;
  for (const LidarConfig& c : {Rosette(20000), mid360}) {
    const Lidar lidar(c, scene);
    const LidarCoverage cover = FramesToCover(lidar, cell, 1.0, 20.0);
    const double reached_sr = static_cast<double>(cover.field_cells) * cell * cell;
    CHECK(reached_sr > 0.97 * c.FieldSolidAngleSr());
    CHECK(reached_sr < 1.12 * c.FieldSolidAngleSr());
  }
  // A spinning LiDAR's band between its lowest and highest channel.
  LidarConfig spinning;
  spinning.vertical_min_deg = -15.0;
  spinning.vertical_max_deg = 45.0;
  CHECK(spinning.FieldSolidAngleSr() ==
        Approx(2.0 * kPi * (std::sin(kPi / 4.0) + std::sin(kPi / 12.0))));
  spinning.vertical_angles_deg = std::vector<double>(32, 0.0);
  spinning.vertical_angles_deg.front() = -10.0;
  spinning.vertical_angles_deg.back() = 30.0;
  CHECK(spinning.FieldSolidAngleSr() ==
        Approx(2.0 * kPi * (std::sin(kPi / 6.0) + std::sin(kPi / 18.0))));
}

}  // namespace
}  // namespace uavsim::sensors
