// FisheyeStereo's static-scene cache against the full render (the cache
// off) in the same scene: frames must be equal bit for bit, in the 8-bit
// images and in the linear radiance under them, over many time steps with
// UAVs and birds near, far, across the image border, behind a building,
// behind the camera and around the eye, in every weather.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "core/world_geometry.h"
#include "sensors/fisheye_stereo.h"
#include "test_support.h"

namespace uavsim::sensors {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;
using testing::BoxMesh;

constexpr double kPi = 3.14159265358979323846;

// A street with a few buildings; the camera stands at (0, 0, 1.5).
core::WorldGeometry Street() {
  core::WorldGeometry w;
  w.meshes.push_back(
      BoxMesh({-200, -200, -0.5f}, {200, 200, 0}, core::kMaterialGround));  // the ground
  w.meshes.push_back(BoxMesh({30, -5, 0}, {40, 5, 20}, core::kMaterialConcrete));
  w.meshes.push_back(BoxMesh({10, 12, 0}, {25, 20, 12}, core::kMaterialConcrete));
  w.meshes.push_back(BoxMesh({-30, -25, 0}, {-15, -12, 25}, core::kMaterialConcrete));
  w.meshes.push_back(BoxMesh({60, -40, 0}, {80, -20, 35}, core::kMaterialConcrete));
  return w;
}

// A linear path from a to b over t in [0, 1], tumbling as it goes (so the
// mesh's extent in every direction matters).
RaycastScene::PoseFunction Path(const Vector3d& a, const Vector3d& b, double tumble = 1.0) {
  return [a, b, tumble](double t) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() =
        (Eigen::AngleAxisd(2.0 * kPi * t * tumble, Vector3d::UnitZ()) *
         Eigen::AngleAxisd(0.7 * tumble * std::sin(5.0 * t), Vector3d(1, 1, 0).normalized()))
            .toRotationMatrix();
    X.translation() = a + t * (b - a);
    return X;
  };
}

// A circle of radius r around the camera at height z, from az0 to az1 (deg).
RaycastScene::PoseFunction Arc(double r, double z, double az0_deg, double az1_deg) {
  return [=](double t) {
    const double az = (az0_deg + t * (az1_deg - az0_deg)) * kPi / 180.0;
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::AngleAxisd(az, Vector3d::UnitZ()).toRotationMatrix();
    X.translation() = Vector3d(r * std::cos(az), r * std::sin(az), z);
    return X;
  };
}

struct MovingObject {
  core::TriangleMesh mesh;
  RaycastScene::PoseFunction X_WO;
};

const core::TriangleMesh kUav = core::MakeQuadrotorMesh({0.5, 0.5, 0.2});

// Every moving object of the scenes below. The camera looks east (+x),
// 20 degrees up; xi 1 sees a little beyond 90 degrees off axis.
std::vector<MovingObject> AllObjects() {
  return {
      {kUav, Path({3, -6, 2.5}, {3, 6, 2.0})},            // near: 3 m, across the view
      {kUav, Path({120, -40, 20}, {140, 40, 35})},        // far: 120-150 m
      {kUav, Arc(15, 6, -40, -200)},                      // off the image's side, behind
      {kUav, Path({50, -15, 8}, {50, 15, 8})},            // behind the building at x 30-40
      {kUav, Path({-12, 3, 4}, {-12, -3, 5})},            // behind the camera
      {kUav, Path({-5, 0.2, 1.6}, {5, -0.2, 1.4}, 0.3)},  // through the eye
      {core::MakeBirdMesh(0.9), Path({20, 15, 15}, {45, -10, 22})},
      {core::MakeBirdMesh(0.5), Path({8, -10, 6}, {12, 10, 9})},
      {core::MakeBirdMesh(0.3), Path({70, 30, 30}, {60, -30, 25})},
  };
}

FisheyeStereoConfig SmallCamera() {
  FisheyeStereoConfig c;  // the default lens, at half resolution
  c.width_px = 320;
  c.height_px = 240;
  c.fx_px = c.fy_px = 115;
  c.cx_px = 160;
  c.cy_px = 120;
  c.pose.position_m = {0, 0, 1.5};
  c.pose.rpy_deg = {0, -20, 0};
  return c;
}

// How many entries differ in their bits (so -0 and 0, or two NaNs, count).
template <typename T>
std::size_t BitDifferences(const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(T)) != 0;
  return n;
}

struct Pair {
  RaycastScene& scene;
  FisheyeStereo cached, full;
  // subsample: as the run wires it, every moving object's sphere is
  // integrated over its pixels (those pixels are re-rendered every frame,
  // cache or not); without it, every pixel of a moving object comes from the
  // cache's re-cast packets.
  Pair(const FisheyeStereoConfig& c, RaycastScene& s, bool subsample = true)
      : scene(s), cached(c, s), full(c, s) {
    full.set_static_cache(false);
    if (!subsample) return;
    auto spheres = [&s](double) { return s.moving_object_bounds(); };
    cached.set_small_objects(spheres);
    full.set_small_objects(spheres);
  }
};

struct Steps {
  int count = 48;
  double t0 = 0.0, t1 = 1.0;
};

// Renders `steps` frames with both cameras and requires equal images and
// radiance; returns the rays the cached camera cast over all frames.
std::size_t CompareFrames(Pair& p, const core::WeatherConfig& weather, const Steps& steps,
                          std::uint64_t seed) {
  core::RngStream noise_cached(seed, "camera"), noise_full(seed, "camera");
  std::size_t rays = 0;
  for (int k = 0; k < steps.count; ++k) {
    const double t = steps.t0 + (steps.t1 - steps.t0) * k / std::max(1, steps.count - 1);
    p.scene.SetTime(t);
    const StereoFrame a = p.cached.Capture(t, weather, noise_cached);
    rays += p.cached.last_capture_rays();
    const StereoFrame b = p.full.Capture(t, weather, noise_full);
    CHECK(p.full.last_capture_rays() >= p.full.rays_per_frame());
    const std::vector<float> ra = p.cached.CaptureRadiance(t, weather);
    const std::vector<float> rb = p.full.CaptureRadiance(t, weather);
    INFO("step " << k << ", t " << t);
    const std::size_t left = BitDifferences(a.left.pixels, b.left.pixels);
    const std::size_t right = BitDifferences(a.right.pixels, b.right.pixels);
    const std::size_t radiance = BitDifferences(ra, rb);
    INFO("differing pixels: left " << left << ", right " << right << "; radiance " << radiance);
    REQUIRE(left == 0);
    REQUIRE(right == 0);
    REQUIRE(radiance == 0);
  }
  return rays;
}

core::WeatherConfig Fog(double visibility_m) {
  core::WeatherConfig w;
  w.fog_visibility_m = visibility_m;
  return w;
}

core::WeatherConfig Rain(double mm_h) {
  core::WeatherConfig w;
  w.rain_mm_h = mm_h;
  return w;
}

core::WeatherConfig Night() {
  core::WeatherConfig w;
  w.illumination = 0.01;
  return w;
}

}  // namespace

TEST_CASE("FisheyeStereo cache: frames equal the full render's bit for bit, in every weather",
          "[sensors][slow]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  for (const MovingObject& o : AllObjects()) scene.AddMovingObject(o.mesh, o.X_WO);
  FisheyeStereoConfig c = SmallCamera();

  SECTION("sub-pixel integration and noise on; clear, fog, rain, night, clear again") {
    Pair p(c, scene);
    CompareFrames(p, {}, {}, 1);
    CompareFrames(p, Fog(150), {}, 2);
    CompareFrames(p, Rain(25), {}, 3);
    CompareFrames(p, Night(), {}, 4);
    CompareFrames(p, {}, {8, 0.2, 0.3}, 5);
  }
  SECTION("no sub-pixel integration, noise off; clear, night, fog with rain") {
    c.sensor_noise = false;
    Pair p(c, scene, false);
    CompareFrames(p, {}, {}, 1);
    CompareFrames(p, Night(), {24, 0.0, 1.0}, 1);
    core::WeatherConfig both = Fog(400);
    both.rain_mm_h = 10;
    CompareFrames(p, both, {}, 2);
  }
  SECTION("the default lens at full resolution, one thread against many") {
    c.width_px = 640;
    c.height_px = 480;
    c.fx_px = c.fy_px = 230;
    c.cx_px = 320;
    c.cy_px = 240;
    Pair p(c, scene);
    p.cached.set_max_threads(1);
    CompareFrames(p, {}, {16, 0.0, 1.0}, 6);
  }
  SECTION("a lens seeing far behind its axis (xi 2), looking straight up") {
    c.xi = 2.0;
    c.pose.rpy_deg = {0, -90, 0};
    Pair p(c, scene, false);
    CompareFrames(p, Rain(5), {24, 0.0, 1.0}, 7);
  }
}

TEST_CASE("FisheyeStereo cache: an eye inside a moving object's sphere renders every pixel",
          "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  // Passes through the left eye at t = 0.5.
  scene.AddMovingObject(kUav, Path({-1, 0, 1.5}, {1, 0, 1.5}));
  Pair p(SmallCamera(), scene, false);
  const std::size_t valid = p.cached.rays_per_frame() / 2;
  core::RngStream noise(1, "camera");
  p.cached.Capture(0.0, {}, noise);  // builds the cache
  scene.SetTime(0.5);
  p.cached.Capture(0.5, {}, noise);
  // The left eye casts all its pixels.
  CHECK(p.cached.last_capture_rays() >= valid);
  scene.SetTime(0.0);
  p.cached.Capture(0.0, {}, noise);
  CHECK(p.cached.last_capture_rays() < valid / 20);
  CompareFrames(p, {}, {21, 0.4, 0.6}, 3);
}

TEST_CASE("FisheyeStereo cache: one small UAV in view re-casts a few hundred rays a frame",
          "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  scene.AddMovingObject(kUav, Path({40, -20, 25}, {40, 20, 25}));
  Pair p(SmallCamera(), scene);
  core::RngStream noise(1, "camera");
  p.cached.Capture(0.0, {}, noise);
  // The first frame builds the cache: every pixel once against the static
  // world, then the packets around the UAV.
  CHECK(p.cached.last_capture_rays() > p.cached.rays_per_frame());
  std::size_t most = 0;
  for (int k = 1; k <= 10; ++k) {
    const double t = 0.1 * k;
    scene.SetTime(t);
    p.cached.Capture(t, {}, noise);
    most = std::max(most, p.cached.last_capture_rays());
    CHECK(p.cached.last_capture_rays() > 0);  // the UAV is in view of both eyes
  }
  INFO("at most " << most << " of " << p.cached.rays_per_frame() << " rays a frame");
  CHECK(most * 50 < p.cached.rays_per_frame());
  // The full render casts every pixel.
  p.full.Capture(0.5, {}, noise);
  CHECK(p.full.last_capture_rays() >= p.full.rays_per_frame());
  CompareFrames(p, Fog(300), {12, 0.0, 1.0}, 4);
}

TEST_CASE("FisheyeStereo cache: a camera above the static world renders every pixel", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  for (const MovingObject& o : AllObjects()) scene.AddMovingObject(o.mesh, o.X_WO);
  FisheyeStereoConfig c = SmallCamera();
  c.pose.position_m = {0, 0, 40};  // above the tallest building (35 m)
  c.pose.rpy_deg = {0, 30, 0};     // looking down
  Pair p(c, scene);
  core::RngStream noise(1, "camera");
  scene.SetTime(0.0);
  p.cached.Capture(0.0, {}, noise);
  CHECK(p.cached.last_capture_rays() >= p.cached.rays_per_frame());
  CompareFrames(p, {}, {12, 0.0, 1.0}, 5);
}

TEST_CASE("RaycastScene: moving objects' spheres enclose their meshes as posed", "[sensors]") {
  core::WorldGeometry world = Street();
  RaycastScene scene(world);
  const std::vector<MovingObject> objects = AllObjects();
  for (const MovingObject& o : objects) scene.AddMovingObject(o.mesh, o.X_WO);
  for (double t : {0.0, 0.37, 1.0}) {
    scene.SetTime(t);
    const std::vector<BoundingSphere>& bounds = scene.moving_object_bounds();
    REQUIRE(bounds.size() == objects.size());
    for (std::size_t k = 0; k < objects.size(); ++k) {
      const Eigen::Isometry3d X = objects[k].X_WO(t);
      CHECK((bounds[k].center_m - X.translation()).norm() < 1e-12);
      double farthest_m = 0.0;
      for (const Vector3f& v : objects[k].mesh.vertices_m)
        farthest_m = std::max(farthest_m, (X * v.cast<double>() - bounds[k].center_m).norm());
      CHECK(farthest_m <= bounds[k].radius_m + 1e-12);
      CHECK(farthest_m >= bounds[k].radius_m - 1e-9);
    }
  }
  // A bird's wing tips reach past half its span (swept back), so half the
  // span is not a bounding radius: 0.514 span.
  CHECK(scene.moving_object_bounds()[6].radius_m > 0.5 * 0.9 * 1.02);
}

}  // namespace uavsim::sensors
