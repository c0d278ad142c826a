// UAV trajectories. Position, velocity and acceleration are closed-form
// functions of time (no integration, so no drift), and each type keeps to its
// configured speed and acceleration limits:
//   waypoints  polyline through the points; along each leg a trapezoidal
//              speed profile that starts and ends at rest, so the path passes
//              every point exactly with continuous velocity, |v| <= max_speed,
//              |a| <= max_accel; `loop` returns to the first point and repeats,
//              otherwise the UAV hovers at the last point.
//   orbit      circle about center_m at constant speed; validation refuses
//              speed > max_speed or v^2/r > max_accel.
//   figure8    Gerono lemniscate x = A sin(wt), y = (B/2) sin(2wt) about
//              center_m, rotated by heading_deg, period period_s; validation
//              refuses a peak speed or acceleration above the limits.
//   random     per axis a sum of sinusoids with seeded frequencies and
//              phases, scaled so the UAV stays inside [min_m, max_m] and keeps
//              |v| <= max_speed, |a| <= max_accel; smooth (C-infinity).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/rng.h"

namespace uavsim::core {

enum class TrajectoryType { kWaypoints, kOrbit, kFigure8, kRandom };

struct TrajectoryConfig {
  TrajectoryType type = TrajectoryType::kOrbit;
  // Limits, shared by all types.
  double max_speed_mps = 10.0;
  double max_accel_mps2 = 5.0;
  // orbit and figure8
  Eigen::Vector3d center_m{0.0, 0.0, 30.0};
  // orbit
  double radius_m = 25.0;
  double speed_mps = 6.0;
  bool clockwise = false;
  double phase_deg = 0.0;
  // figure8: full extent along its own x and y axes
  Eigen::Vector2d size_m{50.0, 30.0};
  double period_s = 40.0;
  double heading_deg = 0.0;
  // waypoints
  std::vector<Eigen::Vector3d> points_m{{-20, -10, 25}, {20, -10, 30}, {20, 15, 35}, {-20, 15, 30}};
  bool loop = true;
  // random: the box to stay in
  Eigen::Vector3d min_m{-30.0, -30.0, 15.0};
  Eigen::Vector3d max_m{30.0, 30.0, 50.0};
  int components = 4;  // sinusoids per axis
};

template <class V>
void Visit(V& v, TrajectoryConfig& c);

struct KinematicState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration_mps2 = Eigen::Vector3d::Zero();
};

class Trajectory {
 public:
  virtual ~Trajectory() = default;
  // State at time t_s >= 0 seconds since the start of the run.
  virtual KinematicState StateAt(double t_s) const = 0;
};

// Builds the trajectory; `rng` is only used by `random`. The config must have
// passed validation (Visit with a JsonReader); throws std::invalid_argument
// otherwise.
std::unique_ptr<Trajectory> MakeTrajectory(const TrajectoryConfig& config, RngStream rng);

}  // namespace uavsim::core
