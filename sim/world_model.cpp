#include "sim/world_model.h"

#include <cmath>

namespace uavsim::sim {
namespace {

constexpr double kGravity_mps2 = 9.80665;

// Birds: smooth random flight over the city, each in its own stream.
core::TrajectoryConfig BirdFlight() {
  core::TrajectoryConfig c;
  c.type = core::TrajectoryType::kRandom;
  c.min_m = {-70.0, -70.0, 8.0};
  c.max_m = {70.0, 70.0, 45.0};
  c.max_speed_mps = 12.0;
  c.max_accel_mps2 = 6.0;
  return c;
}

}  // namespace

Eigen::Isometry3d MultirotorPose(const core::KinematicState& x) {
  const Eigen::Vector3d thrust = x.acceleration_mps2 + Eigen::Vector3d(0, 0, kGravity_mps2);
  const Eigen::Vector3d z_b = thrust.normalized();
  Eigen::Vector3d heading(x.velocity_mps.x(), x.velocity_mps.y(), 0.0);
  if (heading.norm() < 1e-3) heading = Eigen::Vector3d::UnitX();
  Eigen::Vector3d y_b = z_b.cross(heading.normalized());
  if (y_b.norm() < 1e-9) y_b = Eigen::Vector3d::UnitY();
  y_b.normalize();
  const Eigen::Vector3d x_b = y_b.cross(z_b);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear().col(0) = x_b;
  X.linear().col(1) = y_b;
  X.linear().col(2) = z_b;
  X.translation() = x.position_m;
  return X;
}

WorldModel::WorldModel(const Scenario& s)
    : geometry_(core::BuildWorldGeometry(s.world, s.base_dir, core::RngStream(s.seed, "world"))),
      scene_(std::make_unique<sensors::RaycastScene>(geometry_)),
      targets_(TargetIndices(s)),
      target_(FirstTarget(s)) {
  for (const UavConfig& uav : s.uavs) {
    uav_trajectories_.push_back(core::MakeTrajectory(
        uav.trajectory, core::RngStream(s.seed, "uav/" + uav.id + "/trajectory")));
    const core::Trajectory* traj = uav_trajectories_.back().get();
    uav_radii_m_.push_back(0.5 * uav.size_m.norm());
    moving_ids_.push_back(
        scene_->AddMovingObject(core::MakeQuadrotorMesh(uav.size_m),
                                [traj](double t) { return MultirotorPose(traj->StateAt(t)); }));
  }
  for (int i = 0; i < s.distractors.birds; ++i) {
    core::RngStream rng(s.seed, "bird/" + std::to_string(i) + "/trajectory");
    const double span_m = rng.Uniform(0.3, 0.9);  // pigeon to gull
    bird_trajectories_.push_back(core::MakeTrajectory(BirdFlight(), rng));
    const core::Trajectory* traj = bird_trajectories_.back().get();
    bird_radii_m_.push_back(0.5 * span_m);
    moving_ids_.push_back(scene_->AddMovingObject(core::MakeBirdMesh(span_m), [traj](double t) {
      const core::KinematicState x = traj->StateAt(t);
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      const double yaw = std::atan2(x.velocity_mps.y(), x.velocity_mps.x());
      X.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      X.translation() = x.position_m;
      return X;
    }));
  }
  scene_->SetTime(0.0);
}

bool WorldModel::Blocked(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m) const {
  const Eigen::Vector3d d = b_m - a_m;
  const double len = d.norm();
  if (len < 2.5) return false;
  return scene_->Occluded(a_m, b_m, 1.0);
}

std::vector<sensors::BoundingSphere> WorldModel::SmallObjects(double t_s) const {
  std::vector<sensors::BoundingSphere> spheres;
  for (std::size_t i = 0; i < uav_count(); ++i)
    spheres.push_back({uav(i).StateAt(t_s).position_m, uav_radius_m(i)});
  for (std::size_t i = 0; i < bird_count(); ++i)
    spheres.push_back({bird(i).StateAt(t_s).position_m, bird_radius_m(i)});
  return spheres;
}

}  // namespace uavsim::sim
