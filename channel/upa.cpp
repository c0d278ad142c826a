#include "channel/upa.h"

#include <Eigen/Geometry>
#include <cmath>

#include "core/physical_constants.h"

namespace uavsim::channel {
namespace {

using core::kPi;

double Radians(double deg) { return deg * kPi / 180.0; }

}  // namespace

Upa::Upa(const UpaConfig& config, const Eigen::Matrix3d& R_WA)
    : mx_(config.mx), my_(config.my), d_(config.spacing_wavelengths), R_WA_(R_WA) {}

Eigen::Matrix3d Upa::Orientation(double boresight_az_deg, double boresight_el_deg) {
  const double az = Radians(boresight_az_deg);
  const double el = Radians(boresight_el_deg);
  const Eigen::Vector3d z(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  // Depends on the azimuth only, so a zenith boresight is not singular.
  const Eigen::Vector3d x(-std::sin(az), std::cos(az), 0.0);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

Upa Upa::FromConfig(const BaseStationConfig& config) {
  return Upa(config.upa, Orientation(config.boresight_az_deg, config.boresight_el_deg));
}

Eigen::Vector3d Upa::Direction(double theta_rad, double phi_rad) {
  return {std::cos(phi_rad) * std::cos(theta_rad), std::cos(phi_rad) * std::sin(theta_rad),
          std::sin(phi_rad)};
}

Eigen::Vector3d Upa::Direction(const DirectionAngles& angles) {
  return Direction(angles.theta_rad, angles.phi_rad);
}

DirectionAngles Upa::Angles(const Eigen::Vector3d& u_A) {
  const Eigen::Vector3d u = u_A.normalized();
  DirectionAngles a;
  const double rho = std::hypot(u.x(), u.y());
  a.phi_rad = std::atan2(u.z(), rho);
  a.theta_rad = rho > 0.0 ? std::atan2(u.y(), u.x()) : 0.0;
  return a;
}

Eigen::VectorXcd Upa::Steering(const Eigen::Vector3d& u_A) const {
  Eigen::VectorXcd a;
  SteeringInto(u_A, &a);
  return a;
}

Eigen::VectorXcd Upa::Steering(double theta_rad, double phi_rad) const {
  return Steering(Direction(theta_rad, phi_rad));
}

void Upa::SteeringInto(const Eigen::Vector3d& u_A, Eigen::VectorXcd* a) const {
  SpatialSteeringInto(d_ * u_A.x(), d_ * u_A.y(), a);
}

void Upa::SpatialSteeringInto(double psi_x, double psi_y, Eigen::VectorXcd* a) const {
  a->resize(size());
  const double kx = 2.0 * kPi * psi_x;
  const double ky = 2.0 * kPi * psi_y;
  const double cx = 0.5 * (mx_ - 1);
  const double cy = 0.5 * (my_ - 1);
  // a = a_y (x) a_x: a_x goes into the first row, then rows are filled from
  // the last down, so row 0 is overwritten last. Each factor is a geometric
  // sequence: two exponentials and a running product instead of one
  // exponential per element (the product drifts by ~1e-16 per step).
  const std::complex<double> step_x = std::polar(1.0, kx);
  std::complex<double> ax = std::polar(1.0, -kx * cx);
  for (int m = 0; m < mx_; ++m, ax *= step_x) (*a)[m] = ax;
  const std::complex<double> step_y = std::polar(1.0, -ky);
  std::complex<double> ay = std::polar(1.0, ky * ((my_ - 1) - cy));
  for (int n = my_ - 1; n >= 0; --n, ay *= step_y)
    for (int m = 0; m < mx_; ++m) (*a)[m + mx_ * n] = (*a)[m] * ay;
}

}  // namespace uavsim::channel
