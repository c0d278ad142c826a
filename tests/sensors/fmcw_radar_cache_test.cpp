// FmcwRadar's static-scene cache against the full cast (the cache off) in
// the same scene: the scatterers must be equal bit for bit over many time
// steps, with UAVs and birds near, far, behind a building, behind the radar,
// beyond its range and through its antenna, with the caller's refinement
// spheres and with multipath.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/world_geometry.h"
#include "sensors/fmcw_radar.h"
#include "test_support.h"

namespace uavsim::sensors {
namespace {

using Eigen::Vector3d;
using testing::BoxMesh;

constexpr double kPi = 3.14159265358979323846;

// A street with a few buildings; the radar stands at (0, 0, 1.5).
core::WorldGeometry Street() {
  core::WorldGeometry w;
  w.meshes.push_back(BoxMesh({-200, -200, -0.5f}, {200, 200, 0}, core::kMaterialGround));
  w.meshes.push_back(BoxMesh({30, -5, 0}, {40, 5, 20}, core::kMaterialConcrete));
  w.meshes.push_back(BoxMesh({10, 12, 0}, {25, 20, 12}, core::kMaterialGlass));
  w.meshes.push_back(BoxMesh({-30, -25, 0}, {-15, -12, 25}, core::kMaterialConcrete));
  w.meshes.push_back(BoxMesh({60, -40, 0}, {80, -20, 35}, core::kMaterialMetal));
  return w;
}

// A linear path from a to b over t in [0, 1], tumbling as it goes.
RaycastScene::PoseFunction Path(const Vector3d& a, const Vector3d& b) {
  return [a, b](double t) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = (Eigen::AngleAxisd(2.0 * kPi * t, Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.7 * std::sin(5.0 * t), Vector3d(1, 1, 0).normalized()))
                     .toRotationMatrix();
    X.translation() = a + t * (b - a);
    return X;
  };
}

const core::TriangleMesh kUav = core::MakeQuadrotorMesh({0.5, 0.5, 0.2});

void AddEveryObject(RaycastScene& scene) {
  scene.AddMovingObject(kUav, Path({4, -6, 3.0}, {4, 6, 2.0}));    // near, across the view
  scene.AddMovingObject(kUav, Path({70, -30, 20}, {85, 30, 30}));  // far, near the range's end
  scene.AddMovingObject(kUav, Path({50, -15, 8}, {50, 15, 8}));    // behind the building at x 30-40
  scene.AddMovingObject(kUav, Path({-12, 3, 4}, {-12, -3, 5}));    // behind the radar
  scene.AddMovingObject(kUav, Path({150, -10, 20}, {150, 10, 20}));  // beyond the range
  scene.AddMovingObject(core::MakeBirdMesh(0.9), Path({20, 15, 15}, {45, -10, 22}));
  scene.AddMovingObject(core::MakeBirdMesh(0.4), Path({8, -10, 6}, {12, 10, 9}));
}

FmcwRadarConfig TestRadar() {
  FmcwRadarConfig c;  // the default AWR1843-class radar: 100 m, 120 x 60 degrees
  c.pose.position_m = {0, 0, 1.5};
  c.pose.rpy_deg = {0, -10, 0};  // looking east, 10 degrees up
  return c;
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// How many scatterers differ in any bit of any field.
std::size_t Differences(const std::vector<Scatterer>& a, const std::vector<Scatterer>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    bool same = SameBits(a[i].rcs_m2, b[i].rcs_m2) && a[i].object == b[i].object &&
                a[i].multipath == b[i].multipath;
    for (int k = 0; k < 3; ++k)
      same = same && SameBits(a[i].position_m[k], b[i].position_m[k]) &&
             SameBits(a[i].velocity_mps[k], b[i].velocity_mps[k]);
    n += !same;
  }
  return n;
}

struct Pair {
  RaycastScene& scene;
  FmcwRadar cached, full;
  Pair(const FmcwRadarConfig& c, RaycastScene& s) : scene(s), cached(c, s), full(c, s) {
    full.set_static_cache(false);
  }
};

// Finds the scatterers of `steps` instants in [t0, t1] with both radars,
// passing the moving objects' spheres as refinement when `refine`, and
// requires them equal; returns the rays the cached radar cast.
std::size_t Compare(Pair& p, int steps, double t0, double t1, bool refine) {
  std::size_t rays = 0;
  for (int k = 0; k < steps; ++k) {
    const double t = t0 + (t1 - t0) * k / std::max(1, steps - 1);
    p.scene.SetTime(t);
    const std::vector<BoundingSphere> spheres =
        refine ? p.scene.moving_object_bounds() : std::vector<BoundingSphere>{};
    const std::vector<Scatterer> a = p.cached.FindScatterers(t, spheres);
    rays += p.cached.last_cast_rays();
    const std::vector<Scatterer> b = p.full.FindScatterers(t, spheres);
    CHECK(p.full.last_cast_rays() >= p.full.rays_per_frame());
    INFO("step " << k << ", t " << t << ": " << a.size() << " and " << b.size() << " scatterers");
    REQUIRE(!b.empty());
    REQUIRE(Differences(a, b) == 0);
  }
  return rays;
}

}  // namespace

TEST_CASE("FmcwRadar cache: scatterers equal the full cast's bit for bit", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  AddEveryObject(scene);
  SECTION("with the caller's refinement spheres, as the run passes them") {
    Pair p(TestRadar(), scene);
    const std::size_t rays = Compare(p, 40, 0.0, 1.0, true);
    // Cheaper than casting every coarse ray each frame, the refined rays
    // (cast either way) included.
    CHECK(rays < 40 * p.cached.rays_per_frame());
  }
  SECTION("without refinement spheres, with ground multipath, at a coarser grid") {
    FmcwRadarConfig c = TestRadar();
    c.ray_density_deg = 0.5;
    c.multipath = true;
    Pair p(c, scene);
    Compare(p, 40, 0.0, 1.0, false);
  }
  SECTION("looking down from a mast, the UAVs crossing its whole field") {
    FmcwRadarConfig c = TestRadar();
    c.pose.position_m = {0, 0, 12};
    c.pose.rpy_deg = {0, 30, 20};
    Pair p(c, scene);
    Compare(p, 24, 0.0, 1.0, true);
  }
}

TEST_CASE("FmcwRadar cache: one UAV in view re-casts a few coarse rays a frame", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  scene.AddMovingObject(kUav, Path({40, -20, 25}, {40, 20, 25}));  // 45-50 m away, in view
  Pair p(TestRadar(), scene);
  scene.SetTime(0.0);
  p.cached.FindScatterers(0.0);
  // The first call builds the cache: every coarse ray against the static
  // world, then the packets around the UAV.
  CHECK(p.cached.last_cast_rays() > p.cached.rays_per_frame());
  std::size_t most = 0;
  for (int k = 1; k <= 10; ++k) {
    const double t = 0.1 * k;
    scene.SetTime(t);
    p.cached.FindScatterers(t);
    most = std::max(most, p.cached.last_cast_rays());
    CHECK(p.cached.last_cast_rays() > 0);  // the UAV's packets, then its refined cells
  }
  INFO("at most " << most << " of " << p.cached.rays_per_frame() << " coarse rays a frame");
  CHECK(most * 10 < p.cached.rays_per_frame());
  Compare(p, 12, 0.0, 1.0, true);
}

TEST_CASE("FmcwRadar cache: a radar inside a moving object's sphere casts every ray", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  scene.AddMovingObject(kUav, Path({-1, 0, 1.5}, {1, 0, 1.5}));  // through the radar at t 0.5
  Pair p(TestRadar(), scene);
  scene.SetTime(0.0);
  p.cached.FindScatterers(0.0);  // builds the cache
  scene.SetTime(0.5);
  p.cached.FindScatterers(0.5);
  CHECK(p.cached.last_cast_rays() >= p.cached.rays_per_frame());
  Compare(p, 21, 0.4, 0.6, false);
}

TEST_CASE("FmcwRadar cache: a radar above the static world casts every ray", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  AddEveryObject(scene);
  FmcwRadarConfig c = TestRadar();
  c.pose.position_m = {0, 0, 40};  // above the tallest building (35 m)
  c.pose.rpy_deg = {0, 40, 0};
  Pair p(c, scene);
  scene.SetTime(0.0);
  p.cached.FindScatterers(0.0);
  CHECK(p.cached.last_cast_rays() >= p.cached.rays_per_frame());
  Compare(p, 8, 0.0, 1.0, false);
}

// The static world's share of the IF cube kept from frame to frame (issue
// 44): cubes with the switch on equal those made with it off, bit for bit,
// in dry weather and in rain (another attenuation: other static echoes),
// with thermal noise and rain clutter. Returns the frames the kept sums
// served.
std::size_t CompareCubes(Pair& p, int frames_per_weather) {
  core::WeatherConfig dry, rain;
  rain.rain_mm_h = 12;
  core::RngStream noise_a(7, "radar"), noise_b(7, "radar");
  int frame = 0;
  for (const core::WeatherConfig* weather : {&dry, &dry, &rain, &dry}) {
    for (int k = 0; k < frames_per_weather; ++k, ++frame) {
      const double t = 0.05 * k;
      p.scene.SetTime(t);
      const std::vector<BoundingSphere> spheres = p.scene.moving_object_bounds();
      const RadarCube a =
          p.cached.Synthesize(p.cached.FindScatterers(t, spheres), *weather, noise_a);
      const RadarCube b = p.full.Synthesize(p.full.FindScatterers(t, spheres), *weather, noise_b);
      INFO("frame " << frame << ", rain " << weather->rain_mm_h);
      REQUIRE(a.data.size() == b.data.size());
      REQUIRE(std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof a.data[0]) == 0);
    }
  }
  CHECK(p.full.static_sum_hits() == 0);
  return p.cached.static_sum_hits();
}

TEST_CASE("FmcwRadar cache: the static world's cube share, bit for bit", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  SECTION("UAVs and birds crossing in front of buildings and the ground") {
    // The refined cells around them see other static hits every frame: the
    // static sums are made again (and must still be the same).
    AddEveryObject(scene);
    Pair p(TestRadar(), scene);
    CompareCubes(p, 6);
  }
  SECTION("a UAV against the sky") {
    // Nothing static behind or around it: the kept sums serve every frame
    // but the first and each change of weather.
    scene.AddMovingObject(kUav, Path({35, 6, 26}, {35, 10, 27}));
    Pair p(TestRadar(), scene);
    CHECK(CompareCubes(p, 6) == 4 * 6 - 3);
  }
}

}  // namespace uavsim::sensors
