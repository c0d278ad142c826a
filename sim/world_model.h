// The simulated world of one run: the static city in the ray-cast scene, the
// UAVs and birds as moving instances posed from their closed-form
// trajectories, and the radio's view of it (a PathOracle over the same
// scene). Built once from the scenario; sensors and the channel read it.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "channel/path_oracle.h"
#include "core/trajectory.h"
#include "core/world_geometry.h"
#include "sensors/raycast_scene.h"
#include "sim/scenario.h"

namespace uavsim::sim {

// Attitude of a multirotor flying a trajectory: body z along the thrust
// (acceleration plus gravity), body x toward the horizontal velocity (or the
// last heading when hovering).
Eigen::Isometry3d MultirotorPose(const core::KinematicState& x);

class WorldModel : public channel::PathOracle {
 public:
  // Streams: "world" (city layout), "uav/<id>/trajectory", "bird/<i>/trajectory".
  explicit WorldModel(const Scenario& scenario);

  sensors::RaycastScene& scene() { return *scene_; }
  const sensors::RaycastScene& scene() const { return *scene_; }
  const core::WorldGeometry& geometry() const { return geometry_; }
  // The target the single-target methods localize: the first UAV whose
  // role is "target" (uavs[0] unless the scenario says otherwise).
  const core::Trajectory& target() const { return *uav_trajectories_[target_]; }
  // Every UAV whose role is "target", in scenario order.
  const std::vector<std::size_t>& targets() const { return targets_; }
  std::size_t uav_count() const { return uav_trajectories_.size(); }
  const core::Trajectory& uav(std::size_t i) const { return *uav_trajectories_[i]; }
  double uav_radius_m(std::size_t i) const { return uav_radii_m_[i]; }  // bounding sphere
  std::size_t bird_count() const { return bird_trajectories_.size(); }
  const core::Trajectory& bird(std::size_t i) const { return *bird_trajectories_[i]; }
  double bird_radius_m(std::size_t i) const { return bird_radii_m_[i]; }
  // The bounding spheres of everything that moves at t_s: the UAVs, then the
  // birds (world ENU, metres).
  std::vector<sensors::BoundingSphere> SmallObjects(double t_s) const;

  // PathOracle: blocked by anything in the scene (city, birds, other UAVs);
  // the segment's ends are trimmed by 1 m so the target's own body and the
  // antenna mast do not count.
  bool Blocked(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m) const override;
  const std::vector<core::Facade>& Reflectors() const override { return geometry_.facades; }

 private:
  core::WorldGeometry geometry_;
  std::unique_ptr<sensors::RaycastScene> scene_;
  std::vector<std::unique_ptr<core::Trajectory>> uav_trajectories_;
  std::vector<std::unique_ptr<core::Trajectory>> bird_trajectories_;
  std::vector<double> uav_radii_m_, bird_radii_m_;
  std::vector<int> moving_ids_;  // scene ids of UAVs then birds
  std::vector<std::size_t> targets_;
  std::size_t target_ = 0;
};

}  // namespace uavsim::sim
