// A rigid pose in the world frame (ENU, metres), as scenarios write it:
// {"position_m": [x, y, z], "rpy_deg": [roll, pitch, yaw]}, with yaw about z,
// then pitch about the new y, then roll about the new x (intrinsic Z-Y'-X'').
// Body frames follow ROS REP 103: x forward, y left, z up.
#pragma once

#include <Eigen/Geometry>

namespace uavsim::core {

struct PoseConfig {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();

  // X_WB: maps body coordinates to world coordinates.
  Eigen::Isometry3d ToIsometry() const;
};

template <class V>
void Visit(V& v, PoseConfig& c);

}  // namespace uavsim::core
