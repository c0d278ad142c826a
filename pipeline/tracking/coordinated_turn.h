// The coordinated-turn motion model (Bar-Shalom, Li & Kirubarajan,
// "Estimation with Applications to Tracking and Navigation", 2001, Sec.
// 11.7, Eq. 11.7.1-4), shared by the filters whose state is
// x = [p, v, a, omega] (world ENU, SI: m, m/s, m/s^2, rad/s): the anchor
// filter (pipeline/anchored/anchor_filter.h) and the `ekf` baseline
// (pipeline/baselines/ekf.h). The horizontal velocity turns at the rate
// omega about the vertical (positive counter-clockwise seen from above), the
// vertical velocity is constant, the acceleration is set to 0 and omega is
// kept:
//   p_xy += [sin(w dt)  -(1 - cos(w dt)); 1 - cos(w dt)  sin(w dt)] v_xy / w,
//   v_xy  = [cos -sin; sin cos](w dt) v_xy,  p_z += v_z dt.
// Any dt (a negative one runs the circle backwards); near omega dt = 0 the
// closed forms give way to their series (the limit omega = 0 is the straight
// line p + v dt). Deterministic, no state, thread-safe.
#pragma once

#include <Eigen/Core>

namespace uavsim::pipeline {

// The state dt ahead (a set to 0) and its Jacobian d next / d x.
void CoordinatedTurn(const Eigen::Matrix<double, 10, 1>& x, double dt,
                     Eigen::Matrix<double, 10, 1>& next, Eigen::Matrix<double, 10, 10>& jacobian);

}  // namespace uavsim::pipeline
