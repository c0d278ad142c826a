#include "pipeline/anchor_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace uavsim::pipeline {

namespace {

// chi-square quantiles at 0.99 for 1 to 4 degrees of freedom.
constexpr double kGate[] = {0.0, 6.635, 9.210, 11.345, 13.277};

}  // namespace

void AnchorFilter::PredictTo(double t_s) {
  const double dt = t_s - t_s_;
  if (dt <= 0.0) return;
  // Per axis, in 3x3 blocks of [p, v, a].
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity(), q;
  f(0, 1) = f(1, 2) = dt;
  const double d2 = dt * dt, d3 = d2 * dt;
  if (motion_ == Motion::kCv) {
    q << kAccelPsd * d3 / 3.0, kAccelPsd * d2 / 2.0, 0.0,  //
        kAccelPsd * d2 / 2.0, kAccelPsd * dt, 0.0,         //
        0.0, 0.0, 0.0;
  } else {
    f(0, 2) = d2 / 2.0;
    const double d4 = d3 * dt, d5 = d4 * dt, j = kJerkPsd;
    q << j * d5 / 20.0, j * d4 / 8.0, j * d3 / 6.0,  //
        j * d4 / 8.0, j * d3 / 3.0, j * d2 / 2.0,    //
        j * d3 / 6.0, j * d2 / 2.0, j * dt;
  }
  Matrix9d big_f, big_q;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      big_f.block<3, 3>(3 * r, 3 * c) = f(r, c) * Eigen::Matrix3d::Identity();
      big_q.block<3, 3>(3 * r, 3 * c) = q(r, c) * Eigen::Matrix3d::Identity();
    }
  x_ = big_f * x_;
  p_ = big_f * p_ * big_f.transpose() + big_q;
  t_s_ = t_s;
}

template <int N>
bool AnchorFilter::Update(const Eigen::Matrix<double, N, 1>& innovation,
                          const Eigen::Matrix<double, N, 9>& jacobian,
                          const Eigen::Matrix<double, N, N>& noise) {
  const Eigen::Matrix<double, N, N> s = jacobian * p_ * jacobian.transpose() + noise;
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(s);
  if (llt.info() != Eigen::Success) return false;
  if (innovation.dot(llt.solve(innovation)) > kGate[N]) return false;
  const Eigen::Matrix<double, 9, N> k = llt.solve(jacobian * p_).transpose();  // P H^T S^-1
  x_ += k * innovation;
  const Matrix9d a = Matrix9d::Identity() - k * jacobian;
  p_ = a * p_ * a.transpose() + k * noise * k.transpose();  // Joseph form
  return true;
}

void AnchorFilter::Start(const Eigen::Vector3d& p, double t_s) {
  started_ = true;
  t_s_ = last_ranging_s_ = t_s;
  rejections_ = 0;
  x_.head<3>() = p;
  x_.tail<6>().setZero();
  p_.setZero();
  p_.diagonal().segment<3>(0).setConstant(kLidarSigma_m * kLidarSigma_m);
  p_.diagonal().segment<3>(3).setConstant(kStartSpeedSigma_mps * kStartSpeedSigma_mps);
  if (motion_ == Motion::kCa)
    p_.diagonal().segment<3>(6).setConstant(kStartAccelSigma_mps2 * kStartAccelSigma_mps2);
}

bool AnchorFilter::AgreesWithRay(Modality m, const GeometricAnchor& a) const {
  return ray_ && AnchorAgreesWithRay(m, a, *ray_);
}

void AnchorFilter::Observe(Modality m, const GeometricAnchor& a) {
  if (a.kind == GeometricAnchor::Kind::kNone) return;
  const bool is_ray = a.kind == GeometricAnchor::Kind::kRay;
  if (is_ray != (m == Modality::kCamera))
    throw std::invalid_argument("AnchorFilter: a camera anchor must be a ray, others points");
  // Coasting past kMaxCoast_s the track still predicts, but any ranging fix
  // that agrees with the ray may take it over.
  const bool live = started_ && a.t_s - last_ranging_s_ <= kMaxCoast_s;
  if (is_ray) {
    ray_ = a;
    if (!started_) return;
    PredictTo(a.t_s);
    // An orthonormal pair normal to the ray.
    const Eigen::Vector3d& d = a.direction_w;
    const Eigen::Vector3d e1 = d.unitOrthogonal();
    const Eigen::Vector3d e2 = d.cross(e1);
    const Eigen::Vector3d r = x_.head<3>() - a.origin_w;
    Eigen::Matrix<double, 2, 9> h = Eigen::Matrix<double, 2, 9>::Zero();
    h.block<1, 3>(0, 0) = e1.transpose();
    h.block<1, 3>(1, 0) = e2.transpose();
    const double rho = std::max(1.0, r.dot(d));
    const double var = std::pow(rho * kRaySigma_rad, 2) + kRayFloor_m * kRayFloor_m;
    Update<2>(-Eigen::Vector2d(e1.dot(r), e2.dot(r)), h, var * Eigen::Matrix2d::Identity());
    return;
  }
  bool accepted = false;
  if (started_) {
    PredictTo(a.t_s);
    if (m == Modality::kLidar) {
      Eigen::Matrix<double, 3, 9> h = Eigen::Matrix<double, 3, 9>::Zero();
      h.leftCols<3>().setIdentity();
      accepted = Update<3>(a.origin_w - x_.head<3>(), h,
                           kLidarSigma_m * kLidarSigma_m * Eigen::Matrix3d::Identity());
    } else {
      // The cluster's direction from the radar at its mean range (its
      // angles are degrees off, its range centimetres) and its radial
      // velocity (u . v at the predicted position).
      const Eigen::Vector3d u = (a.origin_w - a.sensor_w).normalized();
      const Eigen::Matrix3d along = u * u.transpose();
      const double cross = a.range_m * kRadarAngleSigma_rad;
      const Eigen::Matrix3d position_noise = kRangeSigma_m * kRangeSigma_m * along +
                                             cross * cross * (Eigen::Matrix3d::Identity() - along);
      const Eigen::Vector3d z_p = a.sensor_w + a.range_m * u;
      if (a.has_range_rate) {
        const Eigen::Vector3d r = x_.head<3>() - a.sensor_w;
        const double range = std::max(r.norm(), 1e-3);
        const Eigen::Vector3d los = r / range;
        const Eigen::Vector3d v = x_.segment<3>(3);
        Eigen::Matrix<double, 4, 9> h = Eigen::Matrix<double, 4, 9>::Zero();
        h.topLeftCorner<3, 3>().setIdentity();
        h.block<1, 3>(3, 0) = ((v - los.dot(v) * los) / range).transpose();  // d(los . v)/dp
        h.block<1, 3>(3, 3) = los.transpose();
        Eigen::Matrix4d noise = Eigen::Matrix4d::Zero();
        noise.topLeftCorner<3, 3>() = position_noise;
        noise(3, 3) = kRangeRateSigma_mps * kRangeRateSigma_mps;
        Eigen::Vector4d innovation;
        innovation << z_p - x_.head<3>(), a.range_rate_mps - los.dot(v);
        accepted = Update<4>(innovation, h, noise);
      } else {
        Eigen::Matrix<double, 3, 9> h = Eigen::Matrix<double, 3, 9>::Zero();
        h.leftCols<3>().setIdentity();
        accepted = Update<3>(z_p - x_.head<3>(), h, position_noise);
      }
    }
    if (accepted) {
      last_ranging_s_ = t_s_;
      rejections_ = 0;
      pending_.reset();
      return;
    }
    ++rejections_;
  }
  // A (re)start: at a ranging fix that agrees with the ray, put on the ray. A
  // radar's cluster is often something else on the same line of sight, and a
  // static one confirms itself frame after frame: a radar fix starts a track
  // only where none runs, once a second fix confirms it, and never takes
  // one over.
  if ((live && rejections_ < kMaxRejections) || !AgreesWithRay(m, a)) return;
  const Eigen::Vector3d& o = ray_->origin_w;
  const Eigen::Vector3d& d = ray_->direction_w;
  const Eigen::Vector3d p = m == Modality::kLidar
                                ? ProjectOntoRay(a.origin_w, o, d)
                                : RangeOnRay(a.sensor_w, a.range_m, a.origin_w, o, d);
  const bool confirmed = pending_ && (p - pending_->first).norm() <=
                                         kConfirm_m + kMaxSpeed_mps * (a.t_s - pending_->second);
  if (m == Modality::kLidar || (confirmed && !live)) {
    Start(p, std::max(a.t_s, ray_->t_s));
    pending_.reset();
  } else {
    pending_ = std::pair{p, a.t_s};
  }
}

std::optional<AnchorFilter::Estimate> AnchorFilter::PredictAt(double t_s) const {
  if (!started_ || t_s - last_ranging_s_ > kMaxPredict_s) return std::nullopt;
  AnchorFilter copy = *this;
  copy.PredictTo(t_s);
  return Estimate{copy.x_.head<3>(), std::sqrt(copy.p_.topLeftCorner<3, 3>().trace()),
                  std::max(0.0, t_s - last_ranging_s_)};
}

}  // namespace uavsim::pipeline
