#include "sensors/fisheye_model.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/physical_constants.h"

namespace uavsim::sensors {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using core::kPi;

}  // namespace

FisheyeModel::FisheyeModel(const FisheyeStereoConfig& c)
    : width_px_(c.width_px),
      height_px_(c.height_px),
      xi_(c.xi),
      fx_(c.fx_px),
      fy_(c.fy_px),
      cx_(c.cx_px),
      cy_(c.cy_px),
      k1_(c.k1),
      k2_(c.k2),
      p1_(c.p1),
      p2_(c.p2),
      k3_(c.k3) {
  // Mei's lifting returns the sphere point with z_s >= -1/xi, and the
  // projection needs z_s + xi > 0: both hold for z_s > -min(xi, 1/xi).
  min_z_s_ = xi_ > 0.0 ? -std::min(xi_, 1.0 / xi_) : 0.0;
  // For xi > 1 the image of the sphere is the disc r^2 < 1 / (xi^2 - 1)
  // (where 1 + (1 - xi^2) r^2, the lifting's discriminant, stays positive).
  const double mei_r2 = xi_ > 1.0 ? 1.0 / (xi_ * xi_ - 1.0) : kInf;
  max_r2_ = std::min(mei_r2, FoldR2(std::min(std::sqrt(mei_r2), 1e3)));
}

double FisheyeModel::FoldR2(double r_cap) const {
  // Beyond the first radius where the distortion's Jacobian turns singular
  // the lens folds back: two directions would share a pixel. Tangential
  // terms make that radius depend on the direction, so scan 360 of them
  // (geometric steps in r, then bisection) and keep the nearest fold, less
  // 0.1 % so the inverse stays well conditioned up to the rim.
  double fold_r = kInf;
  for (int k = 0; k < 360; ++k) {
    const Eigen::Vector2d dir(std::cos(k * kPi / 180.0), std::sin(k * kPi / 180.0));
    auto regular = [&](double r) { return DistortJacobian(r * dir).determinant() > 0.0; };
    double lo = 0.0;
    for (double r = 1e-4; r <= r_cap; r *= 1.005) {
      if (!regular(r)) {
        double hi = r;
        for (int i = 0; i < 60; ++i) {
          const double mid = 0.5 * (lo + hi);
          (regular(mid) ? lo : hi) = mid;
        }
        fold_r = std::min(fold_r, lo);
        break;
      }
      lo = r;
    }
  }
  return std::isfinite(fold_r) ? 0.999 * fold_r * fold_r : kInf;
}

double FisheyeModel::max_undistorted_radius() const { return std::sqrt(max_r2_); }

Eigen::Vector2d FisheyeModel::Distort(const Eigen::Vector2d& m) const {
  const double x = m.x(), y = m.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1_ + r2 * (k2_ + r2 * k3_));
  return {x * radial + 2.0 * p1_ * x * y + p2_ * (r2 + 2.0 * x * x),
          y * radial + p1_ * (r2 + 2.0 * y * y) + 2.0 * p2_ * x * y};
}

Eigen::Matrix2d FisheyeModel::DistortJacobian(const Eigen::Vector2d& m) const {
  const double x = m.x(), y = m.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1_ + r2 * (k2_ + r2 * k3_));
  const double dradial_dr2 = k1_ + r2 * (2.0 * k2_ + r2 * 3.0 * k3_);
  Eigen::Matrix2d J;
  J(0, 0) = radial + 2.0 * x * x * dradial_dr2 + 2.0 * p1_ * y + 6.0 * p2_ * x;
  J(0, 1) = 2.0 * x * y * dradial_dr2 + 2.0 * p1_ * x + 2.0 * p2_ * y;
  J(1, 0) = 2.0 * x * y * dradial_dr2 + 2.0 * p1_ * x + 2.0 * p2_ * y;
  J(1, 1) = radial + 2.0 * y * y * dradial_dr2 + 6.0 * p1_ * y + 2.0 * p2_ * x;
  return J;
}

std::optional<Eigen::Vector2d> FisheyeModel::Undistort(const Eigen::Vector2d& m_d) const {
  // Fixed-point iteration m_u = (m_d - tangential(m_u)) / radial(m_u), as in
  // cv::omnidir::undistortPoints (20 steps).
  Eigen::Vector2d m = m_d;
  for (int i = 0; i < 20; ++i) {
    const double x = m.x(), y = m.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1_ + r2 * (k2_ + r2 * k3_));
    const Eigen::Vector2d tangential(2.0 * p1_ * x * y + p2_ * (r2 + 2.0 * x * x),
                                     p1_ * (r2 + 2.0 * y * y) + 2.0 * p2_ * x * y);
    m = (m_d - tangential) / radial;
  }
  if (!m.allFinite()) m = m_d;
  // Near the edge of a strongly distorting lens the fixed point contracts
  // slowly (or not at all); Newton steps make the inverse exact to 1e-12, so
  // the ray table inverts Project to far below 1e-6 rad everywhere.
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d residual = Distort(m) - m_d;
    if (residual.norm() < 1e-15) break;
    const Eigen::Matrix2d J = DistortJacobian(m);
    if (std::abs(J.determinant()) < 1e-300) break;
    m -= J.inverse() * residual;
    if (!m.allFinite()) return std::nullopt;
  }
  if ((Distort(m) - m_d).norm() > 1e-10) return std::nullopt;
  return m;
}

std::optional<Eigen::Vector2d> FisheyeModel::Project(const Eigen::Vector3d& p_C) const {
  const double norm = p_C.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return std::nullopt;
  const Eigen::Vector3d x_s = p_C / norm;
  if (!(x_s.z() > min_z_s_)) return std::nullopt;
  const Eigen::Vector2d m_u = x_s.head<2>() / (x_s.z() + xi_);
  if (!(m_u.squaredNorm() < max_r2_)) return std::nullopt;
  const Eigen::Vector2d m_d = Distort(m_u);
  const Eigen::Vector2d px(fx_ * m_d.x() + cx_, fy_ * m_d.y() + cy_);
  if (px.x() < -0.5 || px.x() >= width_px_ - 0.5 || px.y() < -0.5 || px.y() >= height_px_ - 0.5)
    return std::nullopt;
  return px;
}

Eigen::Vector3d FisheyeModel::Unproject(double u, double v) const {
  const std::optional<Eigen::Vector2d> m_u = Undistort({(u - cx_) / fx_, (v - cy_) / fy_});
  if (!m_u) return Eigen::Vector3d::Zero();
  const double r2 = m_u->squaredNorm();
  if (!(r2 < max_r2_)) return Eigen::Vector3d::Zero();
  // Mei 2007: the closed-form lifting of m_u onto the unit sphere.
  const double discriminant = 1.0 + (1.0 - xi_ * xi_) * r2;
  if (discriminant < 0.0) return Eigen::Vector3d::Zero();
  const double eta = (xi_ + std::sqrt(discriminant)) / (r2 + 1.0);
  const Eigen::Vector3d x_s(eta * m_u->x(), eta * m_u->y(), eta - xi_);
  if (!(x_s.z() > min_z_s_)) return Eigen::Vector3d::Zero();
  return x_s.normalized();  // unit already up to rounding
}

RayTable FisheyeModel::ComputeRayTable() const {
  RayTable table;
  table.width_px = width_px_;
  table.height_px = height_px_;
  const std::size_t n = static_cast<std::size_t>(width_px_) * height_px_;
  table.direction_C.assign(n, Eigen::Vector3f::Zero());
  table.valid.assign(n, 0);
  for (int v = 0; v < height_px_; ++v) {
    for (int u = 0; u < width_px_; ++u) {
      const Eigen::Vector3d d = Unproject(u, v);
      if (d.isZero()) continue;
      const std::size_t i = static_cast<std::size_t>(v) * width_px_ + u;
      table.direction_C[i] = d.cast<float>();
      table.valid[i] = 1;
      ++table.valid_count;
    }
  }
  return table;
}

}  // namespace uavsim::sensors
