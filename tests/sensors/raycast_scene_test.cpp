#include "sensors/raycast_scene.h"

#include <catch2/catch.hpp>

#include <cmath>
#include "test_support.h"

#include "core/interrupt.h"
#include "core/rng.h"

using uavsim::core::TriangleMesh;
using uavsim::core::WorldGeometry;
using uavsim::sensors::Ray;
using uavsim::sensors::RaycastScene;

using uavsim::testing::BoxMesh;

namespace {

WorldGeometry GroundAndWall() {
  WorldGeometry w;
  TriangleMesh ground;
  ground.name = "ground";
  ground.material = uavsim::core::kMaterialGround;
  ground.vertices_m = {{-100, -100, 0}, {100, -100, 0}, {100, 100, 0}, {-100, 100, 0}};
  ground.triangles = {{0, 1, 2}, {0, 2, 3}};
  w.meshes.push_back(ground);
  w.meshes.push_back(
      BoxMesh({20, -10, 0}, {22, 10, 15}, uavsim::core::kMaterialConcrete));  // a wall at x = 20
  return w;
}

}  // namespace

TEST_CASE("RaycastScene: distances to a plane and a wall are the analytic ones", "[sensors]") {
  RaycastScene scene(GroundAndWall());
  CHECK(scene.static_triangle_count() == 14);
  // Straight down from 7 m: the ground at t = 7.
  Ray down;
  down.origin_m = {3, 4, 7};
  down.direction = {0, 0, -1};
  auto h = scene.Intersect(down);
  REQUIRE(h.hit());
  CHECK(h.t == Approx(7.0f));
  CHECK(h.object == 0);
  CHECK(h.material == uavsim::core::kMaterialGround);
  CHECK(h.normal_w.z() == Approx(1.0f));
  // Toward the wall at an angle: t = 20 / cos(a) along a unit direction.
  const float a = 0.3f;
  Ray slant;
  slant.origin_m = {0, 0, 2};
  slant.direction = {std::cos(a), std::sin(a), 0};
  h = scene.Intersect(slant);
  REQUIRE(h.hit());
  CHECK(h.t == Approx(20.0f / std::cos(a)).epsilon(1e-5));
  CHECK(h.material == uavsim::core::kMaterialConcrete);
  CHECK(h.normal_w.x() == Approx(-1.0f));  // facing the ray
  // Upward into the sky: a miss.
  Ray up;
  up.origin_m = {0, 0, 2};
  up.direction = {0, 0, 1};
  CHECK_FALSE(scene.Intersect(up).hit());
  // t_max cuts the ray short.
  slant.t_max = 10.0f;
  CHECK_FALSE(scene.Intersect(slant).hit());
}

TEST_CASE("RaycastScene: packets give exactly the single-ray answers", "[sensors]") {
  RaycastScene scene(GroundAndWall());
  uavsim::core::RngStream rng(3, "rays");
  std::vector<Ray> rays(1003);
  for (auto& r : rays) {
    r.origin_m = {static_cast<float>(rng.Uniform(-5, 5)), static_cast<float>(rng.Uniform(-5, 5)),
                  static_cast<float>(rng.Uniform(0.5, 10))};
    r.direction =
        Eigen::Vector3f(static_cast<float>(rng.Normal()), static_cast<float>(rng.Normal()),
                        static_cast<float>(rng.Normal()))
            .normalized();
  }
  std::vector<uavsim::sensors::RayHit> many(rays.size());
  scene.IntersectMany(rays.data(), many.data(), rays.size());
  int hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const auto one = scene.Intersect(rays[i]);
    REQUIRE(one.hit() == many[i].hit());
    if (one.hit()) {
      ++hits;
      CHECK(one.t == many[i].t);
      CHECK(one.material == many[i].material);
    }
  }
  CHECK(hits > 400);  // about half the random directions point down
}

TEST_CASE("RaycastScene: a termination request stops a batch of rays", "[sensors]") {
  // Every sensor casts through IntersectMany, so this is where a SIGTERM
  // reaches a capture in progress.
  RaycastScene scene(GroundAndWall());
  std::vector<Ray> rays(4096);
  for (auto& r : rays) r.direction = {0.0f, 0.0f, -1.0f}, r.origin_m = {0.0f, 0.0f, 5.0f};
  std::vector<uavsim::sensors::RayHit> hits(rays.size());
  uavsim::core::RequestInterrupt();
  CHECK_THROWS_AS(scene.IntersectMany(rays.data(), hits.data(), rays.size()),
                  uavsim::core::Interrupted);
  CHECK_FALSE(hits.front().hit());  // it stopped before casting
  uavsim::core::ClearInterrupt();
  scene.IntersectMany(rays.data(), hits.data(), rays.size());
  CHECK(hits.back().t == Approx(5.0f));
}

TEST_CASE("RaycastScene: a moving object follows its pose function", "[sensors]") {
  RaycastScene scene(GroundAndWall());
  // A 1 m cube moving along +y at 2 m/s, centred at z = 5.
  const int id = scene.AddMovingObject(
      BoxMesh({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f}, uavsim::core::kMaterialDrone),
      [](double t) {
        Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
        X.translation() = Eigen::Vector3d(10, 2 * t, 5);
        X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        return X;
      });
  CHECK(id == 1);
  Ray r;
  r.origin_m = {10, 4, 0.5f};
  r.direction = {0, 0, 1};
  scene.SetTime(0.0);
  CHECK_FALSE(scene.Intersect(r).hit());  // the cube is at y = 0
  scene.SetTime(2.0);                     // now at y = 4, right above the origin of r
  const auto h = scene.Intersect(r);
  REQUIRE(h.hit());
  CHECK(h.object == id);
  CHECK(h.material == uavsim::core::kMaterialDrone);
  CHECK(h.t == Approx(4.0f).epsilon(1e-5));  // bottom face at z = 4.5, from z = 0.5
  CHECK(h.normal_w.z() == Approx(-1.0f).margin(1e-5));
  // Occlusion along a segment through it.
  CHECK(scene.Occluded({10, 4, 1}, {10, 4, 9}));
  CHECK_FALSE(scene.Occluded({10, 4, 1}, {10, 4, 4}));
  CHECK(scene.Occluded({0, 0, 5}, {30, 0, 5}));  // the wall at x = 20
}
