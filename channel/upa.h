// Uniform planar array (UPA): element layout and steering vectors
// a(theta, phi) of paper Sec. VI-C, in the array's own frame A.
//
// Frame A (right-handed): z_A is the boresight (outward panel normal); x_A
// and y_A lie in the panel. Element (m, n), m = 0..Mx-1 along x_A and
// n = 0..My-1 along y_A, sits at
//   r_mn = d lambda (m' x_A + n' y_A),  m' = m - (Mx-1)/2,  n' = n - (My-1)/2,
// so the phase centre is the array centre (BaseStationConfig::position_m);
// d is the spacing in wavelengths. Element index k = m + Mx n (x fastest).
//
// Angles of a direction, unit vector u in A:
//   u(theta, phi) = (cos(phi) cos(theta), cos(phi) sin(theta), sin(phi))
//   theta in (-pi, pi]: azimuth in the panel plane, from x_A towards y_A;
//   phi in [-pi/2, pi/2]: elevation above the panel plane, towards the
//   boresight (phi = pi/2 is broadside; theta is then 0 by convention).
//
// Steering vector (unnormalised, |[a]_k| = 1, ||a||^2 = Mx My):
//   [a(theta, phi)]_k = exp(j 2 pi d (m' cos(phi) cos(theta) + n' cos(phi) sin(theta)))
//                     = exp(j 2 pi r_mn . u / lambda),
// i.e. a = a_y (x) a_x (Kronecker) with [a_x]_m = exp(j 2 pi d m' u_x) and
// [a_y]_n = exp(j 2 pi d n' u_y). It depends on u only through (u_x, u_y): a
// planar array alone cannot tell the front from the back (the channel drops
// paths behind the panel; channel/beam_channel.h).
#pragma once

#include <Eigen/Core>
#include <complex>

#include "channel/base_station_config.h"

namespace uavsim::channel {

struct DirectionAngles {
  double theta_rad = 0.0;  // azimuth in frame A
  double phi_rad = 0.0;    // elevation in frame A
};

class Upa {
 public:
  // R_WA: columns are x_A, y_A, z_A in world coordinates (an orthonormal,
  // right-handed matrix; not checked).
  explicit Upa(const UpaConfig& config, const Eigen::Matrix3d& R_WA = Eigen::Matrix3d::Identity());

  // The array frame of BaseStationConfig: z_A = boresight at azimuth az (from
  // world +x towards +y) and elevation el (above the horizon); x_A =
  // (-sin az, cos az, 0) horizontal; y_A = z_A x x_A.
  static Eigen::Matrix3d Orientation(double boresight_az_deg, double boresight_el_deg);
  // The array of a base station, with its orientation.
  static Upa FromConfig(const BaseStationConfig& config);

  // u(theta, phi) above.
  static Eigen::Vector3d Direction(double theta_rad, double phi_rad);
  static Eigen::Vector3d Direction(const DirectionAngles& angles);
  // The angles of a direction (need not be unit length; non-zero).
  static DirectionAngles Angles(const Eigen::Vector3d& u_A);

  // A world-frame direction expressed in A (R_WA^T dir_W).
  Eigen::Vector3d ToArrayFrame(const Eigen::Vector3d& dir_W) const {
    return R_WA_.transpose() * dir_W;
  }

  // a(u) for a unit direction u_A in frame A (not renormalised).
  Eigen::VectorXcd Steering(const Eigen::Vector3d& u_A) const;
  Eigen::VectorXcd Steering(double theta_rad, double phi_rad) const;
  // Same, into `a` (resized to size()); no allocation once `a` has the size.
  void SteeringInto(const Eigen::Vector3d& u_A, Eigen::VectorXcd* a) const;
  // The same vector by spatial frequencies psi = d u (cycles per element):
  // [a]_k = exp(j 2 pi (m' psi_x + n' psi_y)); SteeringInto(u) is
  // SpatialSteeringInto(d u_x, d u_y).
  void SpatialSteeringInto(double psi_x, double psi_y, Eigen::VectorXcd* a) const;

  int mx() const { return mx_; }
  int my() const { return my_; }
  int size() const { return mx_ * my_; }
  double spacing_wavelengths() const { return d_; }
  const Eigen::Matrix3d& R_WA() const { return R_WA_; }

 private:
  int mx_;
  int my_;
  double d_;
  Eigen::Matrix3d R_WA_;
};

}  // namespace uavsim::channel
