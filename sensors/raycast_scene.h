// The one owner of Embree (version 3). Holds the static world in one BVH,
// built once, and each moving object (UAV, bird) as an instance of its own
// small BVH; SetTime() moves the instances by their pose functions and
// re-commits only the top level (no rebuild of the city). A second top level
// holds the static instance alone, for caches of what never moves.
//
// Thread safety: Intersect/Occluded may be called from many threads at once;
// SetTime and AddMovingObject may not run concurrently with anything on the
// same scene. Views (NewView) share the geometry but not the poses: a sensor
// on another thread poses and casts into its own view while others use
// theirs.
// Errors reported by Embree are thrown as std::runtime_error.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "core/world_geometry.h"

namespace uavsim::sensors {

struct Ray {
  Eigen::Vector3f origin_m = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitX();  // need not be unit; t is in its lengths
  float t_min = 0.0f;
  float t_max = std::numeric_limits<float>::infinity();
};

struct RayHit {
  float t = std::numeric_limits<float>::infinity();  // distance along the ray, in direction lengths
  Eigen::Vector3f normal_w =
      Eigen::Vector3f::Zero();  // unit geometric normal, world frame, facing the ray
  std::int32_t object =
      -1;  // -1: miss; 0: static world; k >= 1: moving object k (AddMovingObject's id)
  std::uint32_t material = 0;
  bool hit() const { return object >= 0; }
};

// A sphere enclosing a moving object (world frame, ENU metres): sensors use
// it to sample small objects more densely than their regular ray grid.
struct BoundingSphere {
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  double radius_m = 0.0;
};

class RaycastScene {
 public:
  using PoseFunction = std::function<Eigen::Isometry3d(double t_s)>;  // X_WO at time t

  explicit RaycastScene(const core::WorldGeometry& world);
  ~RaycastScene();
  RaycastScene(const RaycastScene&) = delete;
  RaycastScene& operator=(const RaycastScene&) = delete;

  // Adds a moving object: `mesh` in its own body frame, posed by `X_WO(t)`.
  // Returns its id (1, 2, ...). Takes effect at the next SetTime.
  int AddMovingObject(const core::TriangleMesh& mesh, PoseFunction X_WO);

  // A scene of the same geometry (the city's BVH and each moving object's,
  // shared, not copied) with poses of its own: SetTime on a view moves
  // nothing in the scene it was made from, nor the other way round. Rays
  // cast into a view posed at t hit exactly what they hit in this scene
  // posed at t. Make views after the last AddMovingObject (objects added
  // later are not in them); a view may outlive this scene.
  std::unique_ptr<RaycastScene> NewView() const;

  // Poses every moving object at t_s and commits the top-level BVH.
  void SetTime(double t_s);
  double time_s() const { return time_s_; }

  // Closest hit along one ray (rtcIntersect1).
  RayHit Intersect(const Ray& ray) const;
  // Closest hits of many rays: coherent rays go through Embree's packet API
  // (groups of 8); hits[i] answers rays[i]. Polls termination requests every
  // 1024 rays: throws core::Interrupted, leaving `hits` partly written.
  void IntersectMany(const Ray* rays, RayHit* hits, std::size_t count) const;
  // As IntersectMany, the same packets, against the static world alone (a
  // top level holding only its instance, built like the full one). For a
  // packet none of whose rays meets a moving object, cast from a point inside
  // static_bounds(), the hits are bit-identical to IntersectMany's: Embree
  // enters the static instance with the same rays in both top levels (see
  // the .cpp).
  void IntersectManyStatic(const Ray* rays, RayHit* hits, std::size_t count) const;
  // True if anything blocks the segment from a to b (ends excluded by `eps_m`).
  bool Occluded(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double eps_m = 1e-3) const;

  // World velocity of the material point of `object` that is at p_W at time
  // t_s (central difference of its pose function over +-1 ms); zero for the
  // static world (object 0).
  Eigen::Vector3d PointVelocity(int object, const Eigen::Vector3d& p_W, double t_s) const;

  // Spheres enclosing every moving object's mesh as posed at the last SetTime
  // (or AddMovingObject): centre the object's origin, radius its farthest
  // vertex from it. Index k - 1 for object k. Exact up to float rounding of
  // the mesh and of Embree's instance transform (about 1e-7 relative).
  const std::vector<BoundingSphere>& moving_object_bounds() const { return moving_bounds_; }
  // The static world's axis-aligned bounds as Embree reports them.
  Eigen::AlignedBox3d static_bounds() const;

  const core::Material& material(std::uint32_t index) const { return materials_[index]; }
  std::size_t moving_object_count() const { return poses_.size(); }
  std::size_t static_triangle_count() const { return static_triangles_; }

 private:
  struct ViewTag {};
  RaycastScene(const RaycastScene& other, ViewTag);

  struct Impl;
  void IntersectPackets(bool static_only, const Ray* rays, RayHit* hits, std::size_t count) const;

  std::unique_ptr<Impl> impl_;
  std::vector<core::Material> materials_;
  std::vector<PoseFunction> poses_;
  std::vector<double> object_radius_m_;  // farthest vertex from the origin, by object id - 1
  std::vector<BoundingSphere> moving_bounds_;
  std::size_t static_triangles_ = 0;
  double time_s_ = 0.0;
};

}  // namespace uavsim::sensors
