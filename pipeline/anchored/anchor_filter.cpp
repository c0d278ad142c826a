#include "pipeline/anchored/anchor_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/physical_constants.h"

namespace uavsim::pipeline {

namespace {

// chi-square quantiles at 0.99 for 1 to 4 degrees of freedom.
constexpr double kGate[] = {0.0, 6.635, 9.210, 11.345, 13.277};
using core::kPi;

}  // namespace

AnchorFilter::AnchorFilter(Motion motion) : motion_(motion) {
  switch (motion) {
    case Motion::kCv:
      models_ = {Model::kCv};
      break;
    case Motion::kCa:
      models_ = {Model::kCa};
      break;
    case Motion::kImm:
      models_ = {Model::kCt, Model::kCv};
      break;
  }
  imm_ = Imm10(std::vector<double>(models_.size(), 1.0 / static_cast<double>(models_.size())));
}

namespace {

using Vector10d = Eigen::Matrix<double, 10, 1>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;

// A per-axis [p, v, a] block m spread over the 10-state: m(r, c) I in
// block (r, c); omega's row and column those of the identity (a transition)
// or zero (a noise).
Matrix10d PerAxis(const Eigen::Matrix3d& m, bool transition) {
  Matrix10d big = transition ? Matrix10d(Matrix10d::Identity()) : Matrix10d(Matrix10d::Zero());
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      big.block<3, 3>(3 * r, 3 * c) = m(r, c) * Eigen::Matrix3d::Identity();
  return big;
}

// White acceleration of spectral density q on [p, v] per axis.
Eigen::Matrix3d WhiteAcceleration(double q, double dt) {
  Eigen::Matrix3d m;
  m << q * dt * dt * dt / 3.0, q * dt * dt / 2.0, 0.0,  //
      q * dt * dt / 2.0, q * dt, 0.0,                   //
      0.0, 0.0, 0.0;
  return m;
}

// A radar fix as a position: the centroid's direction u from the radar at
// the mean range R, with noise sigma_R^2 u u^T + (R sigma_angle)^2 (I - u u^T)
// (its angles are degrees off, its range centimetres).
struct RadarFix {
  Eigen::Vector3d position, u;
  Eigen::Matrix3d noise;
};
RadarFix RadarFixOf(const GeometricAnchor& a) {
  RadarFix f;
  f.u = (a.origin_w - a.sensor_w).normalized();
  f.position = a.sensor_w + a.range_m * f.u;
  const Eigen::Matrix3d along = f.u * f.u.transpose();
  const double cross = a.range_m * AnchorFilter::kRadarAngleSigma_rad;
  f.noise = AnchorFilter::kRangeSigma_m * AnchorFilter::kRangeSigma_m * along +
            cross * cross * (Eigen::Matrix3d::Identity() - along);
  return f;
}

}  // namespace

void AnchorFilter::PredictTo(double t_s) {
  const double dt = t_s - t_s_;
  if (dt <= 0.0) return;
  // IMM mixing (Bar-Shalom et al. Sec. 11.6.6, steps 1-2): the switch
  // probability over dt of a Markov chain leaving a mode at 1/kModeSwitch_s.
  const std::size_t n = imm_.size();
  if (n > 1) {
    const double leave = 1.0 - std::exp(-dt / kModeSwitch_s);
    Eigen::MatrixXd pi(n, n);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j)
        pi(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
            i == j ? 1.0 - leave : leave / static_cast<double>(n - 1);
    imm_.Mix(pi);
  }
  for (std::size_t j = 0; j < n; ++j) {
    Imm10::Mode& mode = imm_.modes()[j];
    Matrix10d f, q;
    Vector10d next;
    if (models_[j] == Model::kCt) {
      CoordinatedTurn(mode.x, dt, next, f);
      q = PerAxis(WhiteAcceleration(kTurnAccelPsd, dt), false);
      q(9, 9) = kTurnRatePsd * dt;
    } else {
      Eigen::Matrix3d f3 = Eigen::Matrix3d::Identity(), q3;
      f3(0, 1) = dt;
      if (models_[j] == Model::kCv) {
        f3(2, 2) = 0.0;  // a stays 0
        q3 = WhiteAcceleration(kAccelPsd, dt);
      } else {
        f3(1, 2) = dt, f3(0, 2) = dt * dt / 2.0;
        const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt, j = kJerkPsd;
        q3 << j * d5 / 20.0, j * d4 / 8.0, j * d3 / 6.0,  //
            j * d4 / 8.0, j * d3 / 3.0, j * d2 / 2.0,     //
            j * d3 / 6.0, j * d2 / 2.0, j * dt;
      }
      f = PerAxis(f3, true);
      q = PerAxis(q3, false);
      next = f * mode.x;
    }
    mode.x = next;
    mode.P = f * mode.P * f.transpose() + q;
  }
  t_s_ = t_s;
  Combine();
}

void AnchorFilter::Combine() {
  const Imm10::Mode combined = imm_.Combined();
  x_ = combined.x;
  p_ = combined.P;
}

template <int N, class Measure>
bool AnchorFilter::Update(const Measure& measure, const Eigen::Matrix<double, N, N>& noise) {
  using VectorN = Eigen::Matrix<double, N, 1>;
  using MatrixN = Eigen::Matrix<double, N, N>;
  {
    const auto [innovation, h] = measure(x_);
    const Eigen::LLT<MatrixN> llt(h * p_ * h.transpose() + noise);
    if (llt.info() != Eigen::Success) return false;
    const double d2 = innovation.dot(llt.solve(innovation));
    if (probe_) {
      if (d2 <= kGate[N]) *probe_ = d2;
      return false;
    }
    if (d2 > kGate[N]) return false;
  }
  // Each mode's Kalman update (Joseph form) and its log-likelihood (IMM
  // step 3): -d^2/2 - log det(2 pi S)/2. Committed once every mode's is.
  std::vector<Imm10::Mode> updated = imm_.modes();
  std::vector<double> log_likelihood(updated.size());
  for (std::size_t j = 0; j < updated.size(); ++j) {
    Imm10::Mode& mode = updated[j];
    const auto [innovation, h] = measure(mode.x);
    const Eigen::LLT<MatrixN> llt(h * mode.P * h.transpose() + noise);
    if (llt.info() != Eigen::Success) return false;
    const VectorN solved = llt.solve(innovation);
    const Eigen::Matrix<double, 10, N> k = llt.solve(h * mode.P).transpose();  // P H^T S^-1
    mode.x += k * innovation;
    const Matrix10d a = Matrix10d::Identity() - k * h;
    mode.P = a * mode.P * a.transpose() + k * noise * k.transpose();
    const MatrixN l = llt.matrixL();
    log_likelihood[j] = -0.5 * innovation.dot(solved) - l.diagonal().array().log().sum() -
                        0.5 * N * std::log(2.0 * kPi);
  }
  imm_.modes() = std::move(updated);
  imm_.UpdateProbabilities(log_likelihood);  // IMM step 4
  Combine();
  return true;
}

void AnchorFilter::Start(const Eigen::Vector3d& p, double t_s, const GeometricAnchor* radar) {
  started_ = true;
  t_s_ = last_ranging_s_ = t_s;
  rejections_ = lidar_rejections_ = 0;
  // At a LiDAR fix on the ray, known to sigma_lidar; at a radar's fix, known
  // as the radar knows it (the ray it agreed with may be up to
  // RayGate::kGateMaxAge_s old: the following rays fix the rest). The
  // velocity: unknown, but along a starting radar's line of sight u its
  // radial velocity.
  Eigen::Vector3d start = p;
  Eigen::Matrix3d p_cov = kLidarSigma_m * kLidarSigma_m * Eigen::Matrix3d::Identity();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Matrix3d v_cov = kStartSpeedSigma_mps * kStartSpeedSigma_mps * Eigen::Matrix3d::Identity();
  if (radar) {
    const RadarFix fix = RadarFixOf(*radar);
    start = fix.position;
    p_cov = fix.noise;
  }
  if (radar && radar->has_range_rate) {
    const Eigen::Vector3d u = (p - radar->sensor_w).normalized();
    const Eigen::Matrix3d along = u * u.transpose();
    v = radar->range_rate_mps * u;
    v_cov = v_cov * (Eigen::Matrix3d::Identity() - along) +
            kRangeRateSigma_mps * kRangeRateSigma_mps * along;
  }
  Imm10::Mode mode;
  mode.x.setZero();
  mode.x.head<3>() = start;
  mode.x.segment<3>(3) = v;
  mode.P.setZero();
  mode.P.topLeftCorner<3, 3>() = p_cov;
  mode.P.block<3, 3>(3, 3) = v_cov;
  if (motion_ == Motion::kCa)
    mode.P.diagonal().segment<3>(6).setConstant(kStartAccelSigma_mps2 * kStartAccelSigma_mps2);
  if (motion_ == Motion::kImm) mode.P(9, 9) = kStartTurnSigma_rps * kStartTurnSigma_rps;
  const std::size_t n = models_.size();
  imm_.Reset(mode, std::vector<double>(n, 1.0 / static_cast<double>(n)));
  Combine();
}

std::optional<double> AnchorFilter::TurnProbability() const {
  if (!started_) return std::nullopt;
  double p = 0.0;
  for (std::size_t j = 0; j < models_.size(); ++j)
    if (models_[j] == Model::kCt) p += imm_.probabilities()[j];
  return p;
}

bool AnchorFilter::AgreesWithRay(Modality m, const GeometricAnchor& a) const {
  return ray_ && AnchorAgreesWithRay(m, a, *ray_);
}

void AnchorFilter::ObserveWindow(const WindowAnchors& anchors) {
  std::vector<std::pair<Modality, const GeometricAnchor*>> ordered;
  for (std::size_t m = 0; m < anchors.size(); ++m)
    for (const GeometricAnchor& a : anchors[m])
      if (a.kind != GeometricAnchor::Kind::kNone)
        ordered.emplace_back(static_cast<Modality>(m), &a);
  std::stable_sort(ordered.begin(), ordered.end(),
                   [](const auto& a, const auto& b) { return a.second->t_s < b.second->t_s; });
  for (const auto& [m, a] : ordered) Observe(m, *a);
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
    ObserveRay(a);
    return;
  }
  if (started_) {
    PredictTo(a.t_s);
    const bool accepted = UpdateRanging(m, a);
    if (m == Modality::kLidar) lidar_rejections_ = accepted ? 0 : lidar_rejections_ + 1;
    if (accepted) {
      last_ranging_s_ = t_s_;
      rejections_ = 0;
      pending_.reset();
      return;
    }
    ++rejections_;
  }
  MaybeRestart(m, a, live);
}

bool AnchorFilter::ObserveRay(const GeometricAnchor& a) {
  ray_ = a;
  if (!started_) return false;
  PredictTo(a.t_s);
  // An orthonormal pair normal to the ray.
  const Eigen::Vector3d& d = a.direction_w;
  const Eigen::Vector3d e1 = d.unitOrthogonal();
  const Eigen::Vector3d e2 = d.cross(e1);
  const double rho = std::max(1.0, (x_.head<3>() - a.origin_w).dot(d));
  const double var = std::pow(rho * kRaySigma_rad, 2) + kRayFloor_m * kRayFloor_m;
  return Update<2>(
      [&](const Vector10d& x) {
        const Eigen::Vector3d r = x.head<3>() - a.origin_w;
        Eigen::Matrix<double, 2, 10> h = Eigen::Matrix<double, 2, 10>::Zero();
        h.block<1, 3>(0, 0) = e1.transpose();
        h.block<1, 3>(1, 0) = e2.transpose();
        return std::pair{Eigen::Vector2d(-e1.dot(r), -e2.dot(r)), h};
      },
      Eigen::Matrix2d(var * Eigen::Matrix2d::Identity()));
}

bool AnchorFilter::UpdateRanging(Modality m, const GeometricAnchor& a) {
  // A position measurement z_p: innovation z_p - p, Jacobian [I 0].
  const auto position = [](const Eigen::Vector3d& z_p) {
    return [z_p](const Vector10d& x) {
      Eigen::Matrix<double, 3, 10> h = Eigen::Matrix<double, 3, 10>::Zero();
      h.leftCols<3>().setIdentity();
      return std::pair{Eigen::Vector3d(z_p - x.head<3>()), h};
    };
  };
  if (m == Modality::kLidar)
    return Update<3>(position(a.origin_w),
                     Eigen::Matrix3d(kLidarSigma_m * kLidarSigma_m * Eigen::Matrix3d::Identity()));
  // The cluster's position (RadarFixOf) and its radial velocity (u . v at
  // the predicted position).
  const RadarFix fix = RadarFixOf(a);
  const Eigen::Matrix3d& position_noise = fix.noise;
  const Eigen::Vector3d& z_p = fix.position;
  if (!a.has_range_rate) return Update<3>(position(z_p), position_noise);
  Eigen::Matrix4d noise = Eigen::Matrix4d::Zero();
  noise.topLeftCorner<3, 3>() = position_noise;
  noise(3, 3) = kRangeRateSigma_mps * kRangeRateSigma_mps;
  return Update<4>(
      [&](const Vector10d& x) {
        const Eigen::Vector3d r = x.head<3>() - a.sensor_w;
        const double range = std::max(r.norm(), 1e-3);
        const Eigen::Vector3d los = r / range;
        const Eigen::Vector3d v = x.segment<3>(3);
        Eigen::Matrix<double, 4, 10> h = Eigen::Matrix<double, 4, 10>::Zero();
        h.topLeftCorner<3, 3>().setIdentity();
        h.block<1, 3>(3, 0) = ((v - los.dot(v) * los) / range).transpose();  // d(los . v)/dp
        h.block<1, 3>(3, 3) = los.transpose();
        Eigen::Vector4d innovation;
        innovation << z_p - x.head<3>(), a.range_rate_mps - los.dot(v);
        return std::pair{innovation, h};
      },
      noise);
}

void AnchorFilter::MaybeRestart(Modality m, const GeometricAnchor& a, bool live) {
  // A (re)start at a ranging fix that agrees with the ray: a LiDAR fix the
  // track rejected means the track is wrong. A radar's cluster is often
  // something else on the same line of sight, and a static one confirms
  // itself frame after frame: a radar fix starts a track only where none
  // runs, once a second fix (at the ray's crossing of its range sphere)
  // confirms it, and never takes one over.
  if ((live && rejections_ < kMaxRejections && lidar_rejections_ < kMaxLidarRejections) ||
      !AgreesWithRay(m, a))
    return;
  const Eigen::Vector3d& o = ray_->origin_w;
  const Eigen::Vector3d& d = ray_->direction_w;
  // The ray crosses the radar's range sphere twice: the crossing nearer the
  // pending fix, or (none) the centroid.
  const Eigen::Vector3d& hint = pending_ ? pending_->first : a.origin_w;
  const Eigen::Vector3d p =
      m == Modality::kLidar ? a.origin_w : RangeOnRay(a.sensor_w, a.range_m, hint, o, d);
  const bool confirmed = pending_ && (p - pending_->first).norm() <=
                                         kConfirm_m + kMaxSpeed_mps * (a.t_s - pending_->second);
  if (m == Modality::kLidar || (confirmed && !live)) {
    Start(p, std::max(a.t_s, ray_->t_s), m == Modality::kRadar ? &a : nullptr);
    pending_.reset();
  } else {
    pending_ = std::pair{p, a.t_s};
  }
}

void AnchorFilter::StartAt(Modality m, const GeometricAnchor& a) {
  if (m == Modality::kCamera || a.kind != GeometricAnchor::Kind::kPoint)
    throw std::invalid_argument("AnchorFilter::StartAt: a LiDAR or radar point, not a ray");
  Start(a.origin_w, a.t_s, m == Modality::kRadar ? &a : nullptr);
  pending_.reset();
}

std::optional<double> AnchorFilter::AssociationCost(Modality m, const GeometricAnchor& a) const {
  std::optional<double> cost;
  if (!started_ || a.kind == GeometricAnchor::Kind::kNone) return cost;
  AnchorFilter copy = *this;
  copy.probe_ = &cost;
  copy.PredictTo(a.t_s);
  if (a.kind == GeometricAnchor::Kind::kRay)
    copy.ObserveRay(a);
  else
    copy.UpdateRanging(m, a);
  return cost;
}

bool AnchorFilter::UpdateWith(Modality m, const GeometricAnchor& a) {
  if (!started_ || a.kind == GeometricAnchor::Kind::kNone) return false;
  if (a.kind == GeometricAnchor::Kind::kRay) return ObserveRay(a);
  PredictTo(a.t_s);
  const bool accepted = UpdateRanging(m, a);
  if (accepted) last_ranging_s_ = t_s_;
  return accepted;
}

AnchorFilter::PositionFix AnchorFilter::PositionFixOf(Modality m, const GeometricAnchor& a) {
  if (m == Modality::kCamera || a.kind != GeometricAnchor::Kind::kPoint)
    throw std::invalid_argument("AnchorFilter::PositionFixOf: a LiDAR or radar point, not a ray");
  if (m == Modality::kLidar)
    return {a.origin_w, kLidarSigma_m * kLidarSigma_m * Eigen::Matrix3d::Identity(), a.t_s};
  const RadarFix fix = RadarFixOf(a);
  return {fix.position, fix.noise, a.t_s};
}

std::optional<double> AnchorFilter::PositionLogLikelihood(const PositionFix& fix) const {
  if (!started_) return std::nullopt;
  AnchorFilter copy = *this;
  copy.PredictTo(fix.t_s);
  const Eigen::Vector3d nu = fix.position_m - copy.x_.head<3>();
  const Eigen::LLT<Eigen::Matrix3d> llt(copy.p_.topLeftCorner<3, 3>() + fix.noise);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const double d2 = nu.dot(llt.solve(nu));
  if (d2 > kGate[3]) return std::nullopt;
  const Eigen::Matrix3d l = llt.matrixL();
  return -0.5 * d2 - l.diagonal().array().log().sum() - 1.5 * std::log(2.0 * kPi);
}

bool AnchorFilter::UpdateWithMixture(const std::vector<PositionFix>& fixes,
                                     const std::vector<double>& beta, double p_d,
                                     double clutter_per_m3) {
  if (!started_ || fixes.empty() || fixes.size() != beta.size()) return false;
  double t_ref = fixes.front().t_s, beta_sum = 0.0;
  for (std::size_t j = 0; j < fixes.size(); ++j) t_ref = std::max(t_ref, fixes[j].t_s);
  for (double b : beta) beta_sum += b;
  if (!(beta_sum > 0.0)) return false;
  PredictTo(t_ref);
  const double beta0 = std::max(0.0, 1.0 - beta_sum);
  std::vector<Imm10::Mode> updated = imm_.modes();
  std::vector<double> log_likelihood(updated.size());
  for (std::size_t mode = 0; mode < updated.size(); ++mode) {
    const Imm10::Mode prior = updated[mode];
    const Eigen::Vector3d v = prior.x.segment<3>(3);
    std::vector<Imm10::Mode> hypotheses;
    double likelihood = (1.0 - p_d) * clutter_per_m3;  // (1 - p_d) lambda + p_d sum_j g_j
    for (std::size_t j = 0; j < fixes.size(); ++j) {
      // The fix moved to t_ref along the predicted velocity.
      const Eigen::Vector3d z = fixes[j].position_m + v * (t_ref - fixes[j].t_s);
      const Eigen::Vector3d nu = z - prior.x.head<3>();
      const Eigen::Matrix3d s3 = prior.P.topLeftCorner<3, 3>() + fixes[j].noise;
      const Eigen::LLT<Eigen::Matrix3d> llt(s3);
      if (llt.info() != Eigen::Success) return false;
      const Eigen::Matrix<double, 10, 3> k = llt.solve(prior.P.topRows<3>()).transpose();
      Imm10::Mode h = prior;
      h.x += k * nu;
      Matrix10d a = Matrix10d::Identity();
      a.leftCols<3>() -= k;
      h.P = a * prior.P * a.transpose() + k * fixes[j].noise * k.transpose();
      hypotheses.push_back(h);
      const Eigen::Matrix3d l = llt.matrixL();
      likelihood += p_d * std::exp(-0.5 * nu.dot(llt.solve(nu)) - l.diagonal().array().log().sum() -
                                   1.5 * std::log(2.0 * kPi));
    }
    // The moment-matched mixture of the prediction and the fixes' updates.
    Imm10::Mode mixed;
    mixed.x = beta0 * prior.x;
    for (std::size_t j = 0; j < fixes.size(); ++j) mixed.x += beta[j] * hypotheses[j].x;
    mixed.x /= beta0 + beta_sum;
    const Vector10d d0 = prior.x - mixed.x;
    mixed.P = beta0 * (prior.P + d0 * d0.transpose());
    for (std::size_t j = 0; j < fixes.size(); ++j) {
      const Vector10d dj = hypotheses[j].x - mixed.x;
      mixed.P += beta[j] * (hypotheses[j].P + dj * dj.transpose());
    }
    mixed.P /= beta0 + beta_sum;
    updated[mode] = mixed;
    log_likelihood[mode] = likelihood > 0.0 ? std::log(likelihood) : -INFINITY;
  }
  imm_.modes() = std::move(updated);
  imm_.UpdateProbabilities(log_likelihood);
  Combine();
  if (beta_sum >= 0.5) last_ranging_s_ = t_s_;
  return true;
}

std::optional<AnchorFilter::Estimate> AnchorFilter::PredictAt(double t_s) const {
  if (!started_ || t_s - last_ranging_s_ > kMaxPredict_s) return std::nullopt;
  AnchorFilter copy = *this;
  copy.PredictTo(t_s);
  return Estimate{copy.x_.head<3>(), std::sqrt(copy.p_.topLeftCorner<3, 3>().trace()),
                  std::max(0.0, t_s - last_ranging_s_), copy.x_.segment<3>(3)};
}

}  // namespace uavsim::pipeline
