#include "pipeline/baselines/ekf.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <unsupported/Eigen/MatrixFunctions>
#include <utility>

#include "core/physical_constants.h"
#include "pipeline/tracking/coordinated_turn.h"

namespace uavsim::pipeline {
namespace {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

using core::kDegToRad;
using core::kPi;
using core::kSpeedOfLight_mps;

// A radar frame's strongest detections used; a UAV at tens of metres spans a
// few range cells, so more are clutter the clustering kept, and the stacked
// update costs the cube of their number.
constexpr std::size_t kMaxRadarDetections = 16;
// A track not yet confirmed is dropped after this many rejections in a row
// by measurements that cannot start a track (camera rays against a radar
// false alarm, at 30 Hz: 0.1 s).
constexpr int kMaxTentativeRejections = 3;

// Covariance of a point spread uniformly over the target's box, level (a
// multirotor tilts by a few degrees) but of unknown yaw: the two horizontal
// axes share the mean of their variances.
Matrix3d ExtentCovariance(const Vector3d& size_m) {
  const double horizontal = (size_m.x() * size_m.x() + size_m.y() * size_m.y()) / 24.0;
  return Vector3d(horizontal, horizontal, size_m.z() * size_m.z() / 12.0).asDiagonal();
}

// Any orthonormal pair normal to the unit vector u, continuous in u away
// from the vertical (lines of sight to an airborne target rarely are).
std::pair<Vector3d, Vector3d> NormalPair(const Vector3d& u) {
  const Vector3d ref = std::abs(u.z()) < 0.9 ? Vector3d::UnitZ() : Vector3d::UnitX();
  const Vector3d e1 = u.cross(ref).normalized();
  return {e1, u.cross(e1)};
}

// Angular covariance (rad^2, 3x3 in the plane normal to the ray b) of a
// one-pixel image error for a ray at its angle from the optical axis.
Matrix3d PixelAngularCovariance(const Vector3d& b, const Vector3d& axis, double focal_px,
                                double xi) {
  const double cos_theta = std::clamp(b.dot(axis), -1.0, 1.0);
  const double theta = std::acos(cos_theta);
  const Eigen::Vector2d s = FisheyeRadPerPixel(theta, focal_px, xi);
  const Vector3d radial_raw = b * cos_theta - axis;
  if (radial_raw.norm() < 1e-9) return s.x() * s.x() * (Matrix3d::Identity() - b * b.transpose());
  const Vector3d radial = radial_raw.normalized();
  const Vector3d tangential = b.cross(radial);
  return s.x() * s.x() * radial * radial.transpose() +
         s.y() * s.y() * tangential * tangential.transpose();
}

struct StereoModel {
  Vector3d eye_left, eye_right, ray_left, ray_right;
  Vector3d axis;  // optical axis, world
  double focal_px, xi, centre_sigma_px, disparity_sigma_px;

  // The rays' components on (e1, e2), the noise of those four numbers.
  Eigen::Matrix4d Noise(const Vector3d& e1, const Vector3d& e2) const {
    Eigen::Matrix<double, 3, 2> E;
    E << e1, e2;
    const Eigen::Matrix2d C = centre_sigma_px * centre_sigma_px * E.transpose() *
                              PixelAngularCovariance(ray_left, axis, focal_px, xi) * E;
    const Eigen::Matrix2d D = disparity_sigma_px * disparity_sigma_px * E.transpose() *
                              PixelAngularCovariance(ray_right, axis, focal_px, xi) * E;
    Eigen::Matrix4d R;
    R << C, C, C, C + D;
    return R;
  }
};

}  // namespace

// --- Sensor models -------------------------------------------------------

RadarResolution RadarResolutionOf(const sensors::FmcwRadarConfig& c) {
  RadarResolution r;
  const double adc_window_us = c.adc_samples / c.sample_rate_msps;
  const double swept_hz = c.bandwidth_mhz * 1e6 * adc_window_us / c.chirp_duration_us;
  const double lambda_m = kSpeedOfLight_mps / (c.carrier_ghz * 1e9);
  const double chirp_period_s = (c.chirp_duration_us + c.idle_time_us) * 1e-6;
  r.range_m = kSpeedOfLight_mps / (2.0 * swept_hz);
  r.velocity_mps = lambda_m / (2.0 * c.chirps_per_frame * chirp_period_s);
  r.max_velocity_mps = lambda_m / (4.0 * chirp_period_s);
  r.direction_cosine_y = 1.0 / (c.nx * c.spacing_x_wavelengths);
  r.direction_cosine_z = 1.0 / (c.ny * c.spacing_y_wavelengths);
  return r;
}

std::optional<PositionFix> LidarCentroidFix(const PointObservation& o,
                                            const sensors::LidarConfig& lidar,
                                            const EkfConfig& config) {
  const std::size_t n = o.count();
  if (n == 0 || o.channels < 3) return std::nullopt;
  std::vector<Vector3d> points(n);
  Vector3d centroid = Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const float* q = &o.values[i * static_cast<std::size_t>(o.channels)];
    points[i] = Vector3d(q[0], q[1], q[2]);
    centroid += points[i];
  }
  centroid /= static_cast<double>(n);
  Matrix3d scatter = Matrix3d::Zero();
  for (const Vector3d& p : points) scatter += (p - centroid) * (p - centroid).transpose();

  const Vector3d los = centroid - o.sensor_position_w;
  const double range_m = std::max(los.norm(), 1e-6);
  const Vector3d u = los / range_m;
  const Matrix3d along = u * u.transpose();
  const Matrix3d across = Matrix3d::Identity() - along;
  const double footprint_m = lidar.beam_divergence_mrad * 1e-3 * range_m;
  const Matrix3d prior = ExtentCovariance(config.target_size_m) +
                         lidar.range_noise_m * lidar.range_noise_m * along +
                         footprint_m * footprint_m / 16.0 * across;
  // Shrinkage towards the prior: a handful of points is the usual case at
  // range, and their sample covariance alone would claim a precision the
  // geometry does not have.
  const double nu = config.lidar_prior_points;
  const double dn = static_cast<double>(n);
  const Matrix3d per_point = (nu * prior + scatter) / std::max(nu + dn - 1.0, 1.0);

  PositionFix fix;
  fix.t_s = o.t_s;
  fix.position_w = centroid;
  fix.covariance_m2 =
      per_point / dn + config.lidar_floor_m * config.lidar_floor_m * Matrix3d::Identity();
  return fix;
}

Eigen::Vector4d RadarMeasurement(const Vector3d& p, const Vector3d& v, const Vector3d& radar_w,
                                 const Matrix3d& R_WR) {
  const Vector3d w = p - radar_w;
  const Vector3d d = R_WR.transpose() * w;
  const double range_m = d.norm();
  Eigen::Vector4d h;
  h << range_m, std::atan2(d.y(), d.x()), std::atan2(d.z(), std::hypot(d.x(), d.y())),
      w.dot(v) / range_m;
  return h;
}

Eigen::Matrix<double, 4, 6> RadarJacobian(const Vector3d& p, const Vector3d& v,
                                          const Vector3d& radar_w, const Matrix3d& R_WR) {
  const Vector3d w = p - radar_w;
  const Vector3d d = R_WR.transpose() * w;
  const double r2 = d.squaredNorm(), r = std::sqrt(r2);
  const double rxy2 = d.x() * d.x() + d.y() * d.y(), rxy = std::sqrt(rxy2);
  Eigen::Matrix3d dsph_dd;                     // rows: range, azimuth, elevation; columns: d
  dsph_dd << d.x() / r, d.y() / r, d.z() / r,  //
      -d.y() / rxy2, d.x() / rxy2, 0.0,        //
      -d.x() * d.z() / (r2 * rxy), -d.y() * d.z() / (r2 * rxy), rxy / r2;
  const Vector3d u = w / r;
  Eigen::Matrix<double, 4, 6> J = Eigen::Matrix<double, 4, 6>::Zero();
  J.block<3, 3>(0, 0) = dsph_dd * R_WR.transpose();
  J.block<1, 3>(3, 0) = ((v - u.dot(v) * u) / r).transpose();
  J.block<1, 3>(3, 3) = u.transpose();
  return J;
}

std::optional<Triangulation> TriangulateMidpoint(const Vector3d& eye_left_w,
                                                 const Vector3d& ray_left_w,
                                                 const Vector3d& eye_right_w,
                                                 const Vector3d& ray_right_w) {
  const Vector3d d1 = ray_left_w.normalized(), d2 = ray_right_w.normalized();
  // Cross products rather than 1 - (d1.d2)^2: stereo rays are nearly
  // parallel, and the dot-product form loses half the digits to cancellation.
  const Vector3d n = d1.cross(d2);
  const double n2 = n.squaredNorm();
  if (n2 < 1e-24) return std::nullopt;
  const Vector3d w = eye_right_w - eye_left_w;
  Triangulation t;
  t.range_left_m = w.cross(d2).dot(n) / n2;
  t.range_right_m = w.cross(d1).dot(n) / n2;
  if (t.range_left_m <= 0.0 || t.range_right_m <= 0.0) return std::nullopt;
  const Vector3d q1 = eye_left_w + t.range_left_m * d1;
  const Vector3d q2 = eye_right_w + t.range_right_m * d2;
  t.point_w = 0.5 * (q1 + q2);
  t.gap_m = (q1 - q2).norm();
  return t;
}

Eigen::Vector2d FisheyeRadPerPixel(double theta_rad, double focal_px, double xi) {
  // r = f sin(th) / (cos(th) + xi): dr/dth = f (1 + xi cos th) / (cos th + xi)^2, and a
  // tangential pixel spans 1 / (r / sin th) = (cos th + xi) / f radians.
  const double c = std::cos(theta_rad);
  const double denom = std::max(c + xi, 1e-6);
  return {denom * denom / (focal_px * std::max(1.0 + xi * c, 1e-6)), denom / focal_px};
}

double ChiSquareQuantile(double p, int dof) {
  if (!(p > 0.0 && p < 1.0) || dof < 1)
    throw std::invalid_argument("ChiSquareQuantile: needs p in (0, 1) and dof >= 1");
  // CDF by the recurrence P(k + 2, x) = P(k, x) - (x/2)^(k/2) e^(-x/2) / Gamma(k/2 + 1)
  // from P(1, x) = erf(sqrt(x/2)) and P(2, x) = 1 - e^(-x/2).
  auto cdf = [dof](double x) {
    if (x <= 0.0) return 0.0;
    const double h = 0.5 * x;
    double value = dof % 2 == 0 ? -std::expm1(-h) : std::erf(std::sqrt(h));
    for (int k = dof % 2 == 0 ? 2 : 1; k < dof; k += 2)
      value -= std::exp(0.5 * k * std::log(h) - h - std::lgamma(0.5 * k + 1.0));
    return value;
  };
  double lo = 0.0, hi = dof + 10.0;
  while (cdf(hi) < p) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// --- The filter ----------------------------------------------------------

Ekf::Ekf(const EkfConfig& config) : config_(config) {
  const EkfMotionModel motion = config_.motion_model;
  modes_.push_back({ModeKind::kCv, CvAccelPsd(), 0.0, config_.imm_cv_sojourn_s});
  if (motion == EkfMotionModel::kImm || motion == EkfMotionModel::kImmCaCt)
    modes_.push_back({ModeKind::kCa, CaJerkPsd(), 0.0, config_.imm_ca_sojourn_s});
  if (motion == EkfMotionModel::kImmCt || motion == EkfMotionModel::kImmCaCt)
    modes_.push_back({ModeKind::kCt, CtAccelPsd(), CtTurnRatePsd(), config_.imm_ct_sojourn_s});
  for (int dof = 0; dof <= 8; ++dof)
    gate_by_dof_.push_back(dof == 0 ? 0.0 : ChiSquareQuantile(config_.gate_probability, dof));
}

double Ekf::CvAccelPsd() const {
  const double fraction = config_.motion_model == EkfMotionModel::kConstantVelocity
                              ? config_.cv_accel_fraction
                              : config_.imm_cv_accel_fraction;
  const double sigma_a = fraction * config_.max_accel_mps2;
  return sigma_a * sigma_a * config_.maneuver_time_s;
}

double Ekf::CaJerkPsd() const {
  const double sigma_da = config_.imm_ca_jerk_fraction * config_.max_accel_mps2;
  return sigma_da * sigma_da / config_.maneuver_time_s;
}

double Ekf::CtAccelPsd() const {
  const double sigma_a = config_.ct_accel_fraction * config_.max_accel_mps2;
  return sigma_a * sigma_a * config_.maneuver_time_s;
}

double Ekf::CtTurnRatePsd() const {
  const double sigma_dw =
      config_.ct_turn_rate_fraction * config_.max_accel_mps2 / config_.max_speed_mps;
  return sigma_dw * sigma_dw / config_.maneuver_time_s;
}

bool Ekf::HasMode(ModeKind kind) const {
  return std::any_of(modes_.begin(), modes_.end(),
                     [kind](const ModeModel& m) { return m.kind == kind; });
}

double Ekf::GateThreshold(int dof) const {
  if (dof < static_cast<int>(gate_by_dof_.size())) return gate_by_dof_[dof];
  return ChiSquareQuantile(config_.gate_probability, dof);
}

int Ekf::AddNode(const std::string& node_id, NodeKind kind) {
  if (node_index_.count(node_id))
    throw std::invalid_argument("Ekf: node \"" + node_id + "\" is already registered");
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  nodes_.back().id = node_id;
  nodes_.back().kind = kind;
  node_index_[node_id] = index;
  return index;
}

void Ekf::AddCamera(const std::string& node_id, const sensors::FisheyeStereoConfig& config) {
  nodes_[AddNode(node_id, NodeKind::kCamera)].camera = config;
}
void Ekf::AddLidar(const std::string& node_id, const sensors::LidarConfig& config) {
  nodes_[AddNode(node_id, NodeKind::kLidar)].lidar = config;
}
void Ekf::AddRadar(const std::string& node_id, const sensors::FmcwRadarConfig& config) {
  nodes_[AddNode(node_id, NodeKind::kRadar)].radar = config;
}
void Ekf::AddPositionSource(const std::string& node_id) { AddNode(node_id, NodeKind::kPosition); }

Ekf::Node& Ekf::NodeOf(const std::string& node_id, NodeKind kind) {
  const auto it = node_index_.find(node_id);
  if (it == node_index_.end()) throw std::invalid_argument("Ekf: unknown node \"" + node_id + "\"");
  Node& node = nodes_[it->second];
  if (node.kind != kind && !(kind == NodeKind::kLidar && node.kind == NodeKind::kRadar))
    throw std::invalid_argument("Ekf: node \"" + node_id +
                                "\" was registered for another kind of observation");
  return node;
}

const EkfNodeStats& Ekf::stats(const std::string& node_id) const {
  const auto it = node_index_.find(node_id);
  if (it == node_index_.end()) throw std::invalid_argument("Ekf: unknown node \"" + node_id + "\"");
  return nodes_[it->second].stats;
}

void Ekf::Observe(const std::string& node_id, const CameraObservation& o) {
  Node& node = NodeOf(node_id, NodeKind::kCamera);
  ++node.stats.observations;
  Enqueue(node, PrepareCamera(node, o));
}

void Ekf::Observe(const std::string& node_id, const PointObservation& o) {
  Node& node = NodeOf(node_id, NodeKind::kLidar);  // or radar
  ++node.stats.observations;
  if (node.kind == NodeKind::kLidar) {
    if (o.channels != 4)
      throw std::invalid_argument("Ekf: LiDAR node \"" + node_id + "\" expects 4 channels, got " +
                                  std::to_string(o.channels));
    Enqueue(node, PrepareLidar(node, o));
  } else {
    if (o.channels != 5)
      throw std::invalid_argument("Ekf: radar node \"" + node_id + "\" expects 5 channels, got " +
                                  std::to_string(o.channels));
    Enqueue(node, PrepareRadar(node, o));
  }
}

void Ekf::Observe(const std::string& node_id, const PositionFix& fix) {
  Node& node = NodeOf(node_id, NodeKind::kPosition);
  ++node.stats.observations;
  Measurement m;
  m.t_s = fix.t_s;
  const Vector3d z = fix.position_w;
  const Matrix3d R = fix.covariance_m2;
  m.components.push_back([z, R](const Vector10d& x) { return LinearPosition(z, R, x); });
  const double v2 = config_.max_speed_mps * config_.max_speed_mps / 3.0;
  m.start = TrackStart{z, R, Vector3d::Zero(), v2 * Matrix3d::Identity()};
  Enqueue(node, std::move(m));
}

Ekf::Linearization Ekf::LinearPosition(const Vector3d& z, const Matrix3d& R, const Vector10d& x) {
  Linearization l;
  l.innovation = z - x.head<3>();
  l.jacobian = MatrixXd::Zero(3, 10);
  l.jacobian.leftCols<3>().setIdentity();
  l.noise = R;
  return l;
}

Ekf::Measurement Ekf::PrepareLidar(const Node& node, const PointObservation& o) const {
  Measurement m;
  m.t_s = o.t_s;
  const std::optional<PositionFix> fix = LidarCentroidFix(o, node.lidar, config_);
  if (!fix) return m;
  const Vector3d z = fix->position_w;
  const Matrix3d R = fix->covariance_m2;
  m.components.push_back([z, R](const Vector10d& x) { return LinearPosition(z, R, x); });
  const double v2 = config_.max_speed_mps * config_.max_speed_mps / 3.0;
  m.start = TrackStart{z, R, Vector3d::Zero(), v2 * Matrix3d::Identity()};
  return m;
}

Ekf::Measurement Ekf::PrepareRadar(const Node& node, const PointObservation& o) const {
  const RadarResolution res = RadarResolutionOf(node.radar);
  const sensors::FmcwRadarConfig& c = node.radar;
  Measurement m;
  // Detections describe the middle of the frame's chirps, t_s their start.
  m.t_s = o.t_s + 0.5 * c.chirps_per_frame * (c.chirp_duration_us + c.idle_time_us) * 1e-6;
  const std::size_t n = o.count();
  if (n == 0) return m;
  const double array_elements = static_cast<double>(c.nx) * c.ny;
  const Matrix3d R_WR = node.radar.pose.ToIsometry().linear();
  const Vector3d s = o.sensor_position_w;
  const double k = config_.radar_sigma_scale;
  const double floor_angle_rad = config_.radar_angle_floor_deg * kDegToRad;
  Eigen::Matrix4d common = Eigen::Vector4d(config_.radar_range_floor_m, floor_angle_rad,
                                           floor_angle_rad, config_.radar_velocity_floor_mps)
                               .array()
                               .square()
                               .matrix()
                               .asDiagonal();
  m.common_noise = common;

  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  auto snr_of = [&o](std::size_t i) { return o.values[i * 5 + 4]; };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return snr_of(a) > snr_of(b); });
  order.resize(std::min(n, kMaxRadarDetections));

  for (std::size_t idx = 0; idx < order.size(); ++idx) {
    const float* q = &o.values[order[idx] * 5];
    const Vector3d p(q[0], q[1], q[2]);
    const double radial_mps = q[3];
    // snr_db is a cell's per-antenna SNR (radar_processor.h: the antennas'
    // powers summed over their summed noise); the array adds coherently.
    const double snr = std::max(1.0, std::pow(10.0, q[4] / 10.0)) * array_elements;
    Eigen::Vector4d z = RadarMeasurement(p, Vector3d::Zero(), s, R_WR);
    z(3) = radial_mps;
    const double range_m = std::max(z(0), 1e-3);
    const double az = z(1), el = z(2);
    // Direction cosines (u_y, u_z) are what the array measures; map their
    // variance to (azimuth, elevation) through the inverse Jacobian.
    const double var_uy = k * k * res.direction_cosine_y * res.direction_cosine_y / (2.0 * snr);
    const double var_uz = k * k * res.direction_cosine_z * res.direction_cosine_z / (2.0 * snr);
    Eigen::Matrix2d J;
    J << std::cos(el) * std::cos(az), -std::sin(el) * std::sin(az), 0.0, std::cos(el);
    if (std::abs(J.determinant()) < 1e-3) continue;  // at the array's end-fire: no angle
    const Eigen::Matrix2d Jinv = J.inverse();
    Eigen::Matrix4d own = Eigen::Matrix4d::Zero();
    own(0, 0) = k * k * res.range_m * res.range_m / (2.0 * snr);
    own.block<2, 2>(1, 1) = Jinv * Eigen::Vector2d(var_uy, var_uz).asDiagonal() * Jinv.transpose();
    own(3, 3) = k * k * res.velocity_mps * res.velocity_mps / (2.0 * snr);
    const Eigen::Matrix4d R = own + common;
    const double v_max = res.max_velocity_mps;
    m.components.push_back([z, R, s, R_WR, v_max](const Vector10d& x) {
      Linearization l;
      const Vector3d pp = x.head<3>(), vv = x.segment<3>(3);
      Eigen::Vector4d y = z - RadarMeasurement(pp, vv, s, R_WR);
      y(1) = std::remainder(y(1), 2.0 * kPi);
      y(3) = std::remainder(y(3), 2.0 * v_max);
      l.innovation = y;
      l.jacobian = MatrixXd::Zero(4, 10);
      l.jacobian.leftCols<6>() = RadarJacobian(pp, vv, s, R_WR);
      l.noise = R;
      return l;
    });
    if (!m.start) {  // the strongest detection
      const double ce = std::cos(el), se = std::sin(el), ca = std::cos(az), sa = std::sin(az);
      Matrix3d dp_dsph;  // radar-frame point w.r.t. (range, azimuth, elevation)
      dp_dsph << ce * ca, -range_m * ce * sa, -range_m * se * ca,  //
          ce * sa, range_m * ce * ca, -range_m * se * sa,          //
          se, 0.0, range_m * ce;
      const Matrix3d Jw = R_WR * dp_dsph;
      const Vector3d u = (p - s).normalized();
      const double v2 = config_.max_speed_mps * config_.max_speed_mps / 3.0;
      m.start =
          TrackStart{p, Jw * R.topLeftCorner<3, 3>() * Jw.transpose(), radial_mps * u,
                     R(3, 3) * u * u.transpose() + v2 * (Matrix3d::Identity() - u * u.transpose())};
    }
  }
  return m;
}

Ekf::Measurement Ekf::PrepareCamera(const Node& node, const CameraObservation& o) const {
  Measurement m;
  m.t_s = o.t_s;
  if (!o.detected) return m;
  StereoModel model;
  model.eye_left = o.eye_left_w;
  model.eye_right = o.eye_right_w;
  model.ray_left = o.bearing_left_w.normalized();
  model.ray_right = o.bearing_right_w.normalized();
  model.axis = node.camera.pose.ToIsometry().linear() * Vector3d::UnitX();  // body x = optical z
  model.focal_px = 0.5 * (node.camera.fx_px + node.camera.fy_px);
  model.xi = node.camera.xi;
  model.centre_sigma_px = config_.camera_centre_sigma_px;
  model.disparity_sigma_px = config_.camera_disparity_sigma_px;

  m.components.push_back([model](const Vector10d& x) {
    const Vector3d p = x.head<3>();
    const Vector3d centre = 0.5 * (model.eye_left + model.eye_right);
    const auto [e1, e2] = NormalPair((p - centre).normalized());
    Eigen::Matrix<double, 2, 3> Et;
    Et << e1.transpose(), e2.transpose();
    Linearization l;
    l.innovation = VectorXd(4);
    l.jacobian = MatrixXd::Zero(4, 10);
    const Vector3d eyes[2] = {model.eye_left, model.eye_right};
    const Vector3d rays[2] = {model.ray_left, model.ray_right};
    for (int i = 0; i < 2; ++i) {
      const Vector3d w = p - eyes[i];
      const double r = w.norm();
      const Vector3d u = w / r;
      l.innovation.segment<2>(2 * i) = Et * (rays[i] - u);
      l.jacobian.block<2, 3>(2 * i, 0) = Et * (Matrix3d::Identity() - u * u.transpose()) / r;
    }
    l.noise = model.Noise(e1, e2);
    return l;
  });

  // A track may start here only where the stereo pair actually ranges.
  const std::optional<Triangulation> tri =
      TriangulateMidpoint(model.eye_left, model.ray_left, model.eye_right, model.ray_right);
  if (tri) {
    const Vector3d centre = 0.5 * (model.eye_left + model.eye_right);
    const auto [e1, e2] = NormalPair((tri->point_w - centre).normalized());
    // The midpoint is smooth in the rays away from parallel: central differences.
    Eigen::Matrix<double, 3, 4> J;
    const double step = 1e-7;
    for (int col = 0; col < 4; ++col) {
      const Vector3d dir = col % 2 == 0 ? e1 : e2;
      Vector3d rays_plus[2] = {model.ray_left, model.ray_right};
      Vector3d rays_minus[2] = {model.ray_left, model.ray_right};
      rays_plus[col / 2] = (rays_plus[col / 2] + step * dir).normalized();
      rays_minus[col / 2] = (rays_minus[col / 2] - step * dir).normalized();
      const auto plus =
          TriangulateMidpoint(model.eye_left, rays_plus[0], model.eye_right, rays_plus[1]);
      const auto minus =
          TriangulateMidpoint(model.eye_left, rays_minus[0], model.eye_right, rays_minus[1]);
      if (!plus || !minus) return m;
      J.col(col) = (plus->point_w - minus->point_w) / (2.0 * step);
    }
    const Matrix3d cov = J * model.Noise(e1, e2) * J.transpose();
    const double sigma_max_m =
        std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Matrix3d>(cov).eigenvalues()(2)));
    if (sigma_max_m <= config_.camera_init_max_relative_sigma * tri->range_left_m) {
      const double v2 = config_.max_speed_mps * config_.max_speed_mps / 3.0;
      m.start = TrackStart{tri->point_w, cov, Vector3d::Zero(), v2 * Matrix3d::Identity()};
    }
  }
  return m;
}

void Ekf::Enqueue(Node& node, Measurement m) {
  m.node = static_cast<int>(&node - nodes_.data());
  m.arrival = node.arrivals++;
  const double t_s = m.t_s;
  if (t_s < horizon_s_) {
    ++node.stats.too_late;
    return;
  }
  if (!m.components.empty()) {
    auto key = [](const Measurement& a) { return std::make_tuple(a.t_s, a.node, a.arrival); };
    const auto at = std::upper_bound(
        buffer_.begin(), buffer_.end(), m,
        [&key](const Measurement& a, const Measurement& b) { return key(a) < key(b); });
    buffer_.insert(at, std::move(m));
  }
  AdvanceHorizon(t_s);
}

void Ekf::AdvanceHorizon(double t_s) {
  horizon_s_ = std::max(horizon_s_, t_s - config_.reorder_window_s);
  std::size_t done = 0;
  // Strictly older only: an observation exactly at the horizon may still
  // arrive and must not find a later one of equal time already committed.
  while (done < buffer_.size() && buffer_[done].t_s < horizon_s_) {
    Apply(committed_, buffer_[done], &nodes_[buffer_[done].node].stats);
    ++done;
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(done));
}

void Ekf::Start(Track& track, const TrackStart& start, double t_s) const {
  Imm10::Mode mode;
  mode.x.setZero();
  mode.x.head<3>() = start.position_m;
  mode.x.segment<3>(3) = start.velocity_mps;
  mode.P.setZero();
  mode.P.topLeftCorner<3, 3>() = start.position_cov;
  mode.P.block<3, 3>(3, 3) = start.velocity_cov;
  mode.P.block<3, 3>(6, 6) =
      config_.max_accel_mps2 * config_.max_accel_mps2 / 3.0 * Matrix3d::Identity();
  // omega uniform over +-a_max / v_max, where a mode models it; else 0 +- 0.
  if (HasMode(ModeKind::kCt)) {
    const double omega_max = config_.max_accel_mps2 / config_.max_speed_mps;
    mode.P(9, 9) = omega_max * omega_max / 3.0;
  }
  // The chain's stationary distribution: each mode in proportion to its
  // sojourn.
  double total_s = 0.0;
  for (const ModeModel& mm : modes_) total_s += mm.sojourn_s;
  std::vector<double> mu;
  for (const ModeModel& mm : modes_) mu.push_back(mm.sojourn_s / total_s);
  track.imm.Reset(mode, std::move(mu));
  track.initialized = true;
  track.confirmed = false;
  track.rejections = 0;
  track.t_s = t_s;
  track.t_last_update_s = t_s;
  track.t_last_anchor_s = t_s;
}

namespace {

using Vector10d = Eigen::Matrix<double, 10, 1>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;

// White acceleration of density q on [p, v] of every axis (CV, and CT's q_a).
void AddWhiteAcceleration(double q, double dt, Matrix10d& Q) {
  const double dt2 = dt * dt, dt3 = dt2 * dt;
  for (int i = 0; i < 3; ++i) {
    const int p = i, v = 3 + i;
    Q(p, p) = q * dt3 / 3.0;
    Q(p, v) = Q(v, p) = q * dt2 / 2.0;
    Q(v, v) = q * dt;
  }
}

// CV and CA: linear, per axis (header comment); omega carried unchanged.
void PredictLinearMode(bool constant_acceleration, double q, double dt, Vector10d& x,
                       Matrix10d& P) {
  Matrix10d F = Matrix10d::Identity();
  Matrix10d Q = Matrix10d::Zero();
  const double dt2 = dt * dt, dt3 = dt2 * dt;
  for (int i = 0; i < 3; ++i) {
    const int p = i, v = 3 + i, a = 6 + i;
    F(p, v) = dt;
    if (!constant_acceleration) {
      F(a, a) = 0.0;
    } else {
      F(p, a) = dt2 / 2.0;
      F(v, a) = dt;
      Q(p, p) = q * dt3 * dt2 / 20.0;
      Q(p, v) = Q(v, p) = q * dt2 * dt2 / 8.0;
      Q(p, a) = Q(a, p) = q * dt3 / 6.0;
      Q(v, v) = q * dt3 / 3.0;
      Q(v, a) = Q(a, v) = q * dt2 / 2.0;
      Q(a, a) = q * dt;
    }
  }
  if (!constant_acceleration) AddWhiteAcceleration(q, dt, Q);
  x = F * x;
  P = F * P * F.transpose() + Q;
}

// CT: Eq. 11.7.1-4 linearised at the mean; q_a on [p, v], q_w dt on omega.
void PredictTurnMode(double q_a, double q_w, double dt, Vector10d& x, Matrix10d& P) {
  Vector10d next;
  Matrix10d F;
  CoordinatedTurn(x, dt, next, F);
  Matrix10d Q = Matrix10d::Zero();
  AddWhiteAcceleration(q_a, dt, Q);
  Q(9, 9) = q_w * dt;
  x = next;
  P = F * P * F.transpose() + Q;
}

}  // namespace

void Ekf::Predict(Track& track, double t_s) const {
  const double dt = t_s - track.t_s;
  if (!(dt > 0.0)) return;
  const int n = static_cast<int>(modes_.size());
  if (n > 1) {
    // Mixing (IMM steps 1-2) with Pi(dt) = exp(Lambda dt): leaving mode i at
    // rate 1 / sojourn_i for any other mode alike.
    Eigen::MatrixXd rates = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        rates(i, j) = (i == j ? -1.0 : 1.0 / (n - 1)) / modes_[i].sojourn_s;
    // A CV mode has no acceleration of its own: mixed into a CA mode it
    // borrows that mode's acceleration statistics (Granstrom, Willett &
    // Bar-Shalom 2015, unequal-dimension mixing) instead of claiming a = 0
    // with certainty, which would shrink the CA mode's acceleration variance.
    // Likewise a mode without turn rate mixed into the CT mode borrows its
    // omega.
    const auto source_of = [this](const std::vector<Imm10::Mode>& prior, std::size_t i,
                                  std::size_t j) {
      Imm10::Mode source = prior[i];
      const auto borrow = [&](Eigen::Index first, Eigen::Index size) {
        source.x.segment(first, size) = prior[j].x.segment(first, size);
        source.P.middleRows(first, size).setZero();
        source.P.middleCols(first, size).setZero();
        source.P.block(first, first, size, size) = prior[j].P.block(first, first, size, size);
      };
      if (modes_[j].kind == ModeKind::kCa && modes_[i].kind != ModeKind::kCa) borrow(6, 3);
      if (modes_[j].kind == ModeKind::kCt && modes_[i].kind != ModeKind::kCt) borrow(9, 1);
      return source;
    };
    track.imm.Mix((rates * dt).exp(), source_of);
  }
  for (int j = 0; j < n; ++j) {
    const ModeModel& mm = modes_[static_cast<std::size_t>(j)];
    Imm10::Mode& mode = track.imm.modes()[static_cast<std::size_t>(j)];
    if (mm.kind == ModeKind::kCt) {
      PredictTurnMode(mm.psd, mm.turn_psd, dt, mode.x, mode.P);
    } else {
      PredictLinearMode(mm.kind == ModeKind::kCa, mm.psd, dt, mode.x, mode.P);
    }
  }
  track.t_s = t_s;
}

void Ekf::Apply(Tracks& tracks, const Measurement& m, EkfNodeStats* stats) const {
  Track& main = tracks.main;
  auto start = [&](Track& track) {
    Start(track, *m.start, m.t_s);
    track.start_node = m.node;
    if (stats && &track == &main) ++stats->initiations;
  };
  // Whether m may confirm `track`: a ranging measurement; unless
  // radar_confirms_itself, for a track a radar started, one of another node
  // when there is one.
  auto confirms = [&](const Track& track) {
    if (!m.start) return false;
    if (config_.radar_confirms_itself || track.start_node < 0 || nodes_.size() < 2) return true;
    return nodes_[static_cast<std::size_t>(track.start_node)].kind != NodeKind::kRadar ||
           m.node != track.start_node;
  };
  if (!main.initialized) {
    if (m.start) start(main);
    return;
  }
  // A confirmed track not updated for max_gap_s is lost: its predicted
  // covariance would open the gate to any false alarm, so it is re-acquired
  // like a new one, through a confirmed candidate.
  const bool lost = main.confirmed && m.t_s - main.t_last_update_s > config_.max_gap_s;
  if (!lost && Update(main, m, stats) > 0) {
    // A second ranging measurement that agrees confirms a start; camera rays
    // alone cannot (a start far along a ray would pass them).
    if (confirms(main)) main.confirmed = true;
    main.rejections = 0;
    return;
  }
  if (!main.confirmed) {  // a start the next measurements do not bear out
    if (m.start) {
      start(main);
    } else if (++main.rejections >= kMaxTentativeRejections) {
      main = Track{};
    }
    return;
  }
  // A confirmed track is kept against clutter while ranging measurements
  // keep agreeing with it (camera rays alone cannot tell a wrong range).
  // Once none has for ranging_timeout_s, a rejected ranging measurement
  // starts a candidate, and a second one that the track rejects too but the
  // candidate accepts replaces the track: a lone false alarm cannot take a
  // good track away.
  if (lost && stats) stats->rejected += m.components.size();
  if (!m.start || (!lost && m.t_s - main.t_last_anchor_s <= config_.ranging_timeout_s)) return;
  Track& candidate = tracks.candidate;
  if (candidate.initialized && m.t_s - candidate.t_last_update_s <= config_.max_gap_s &&
      Update(candidate, m, nullptr) > 0) {
    if (!confirms(candidate)) return;  // its own radar again: not yet
    main = candidate;
    main.confirmed = true;
    candidate = Track{};
    if (stats) ++stats->initiations;
    return;
  }
  start(candidate);
}

int Ekf::Update(Track& track_in, const Measurement& m, EkfNodeStats* stats) const {
  // On a copy: a measurement wholly outside the gate leaves the track as it
  // was (its time included, which bounds coasting from the last update).
  Track track = track_in;
  Predict(track, m.t_s);

  const Imm10::Mode combined = track.imm.Combined();
  const Vector10d& x_bar = combined.x;
  const Matrix10d& P_bar = combined.P;

  std::vector<std::size_t> accepted;
  for (std::size_t k = 0; k < m.components.size(); ++k) {
    const Linearization l = m.components[k](x_bar);
    const MatrixXd S = l.jacobian * P_bar * l.jacobian.transpose() + l.noise;
    const Eigen::LDLT<MatrixXd> ldlt(S);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) continue;
    const double d2 = l.innovation.dot(ldlt.solve(l.innovation));
    const int dof = static_cast<int>(l.innovation.size());
    if (d2 <= GateThreshold(dof)) {
      accepted.push_back(k);
      if (stats) {
        ++stats->accepted;
        stats->nis_sum += d2;
        stats->nis_dof += static_cast<std::size_t>(dof);
      }
    } else if (stats) {
      ++stats->rejected;
    }
  }
  if (accepted.empty()) return 0;

  std::vector<double> log_likelihood(track.imm.size(), 0.0);
  for (std::size_t j = 0; j < track.imm.size(); ++j) {
    Imm10::Mode& mode = track.imm.modes()[j];
    std::vector<Linearization> parts;
    int dim = 0;
    for (std::size_t k : accepted) {
      parts.push_back(m.components[k](mode.x));
      dim += static_cast<int>(parts.back().innovation.size());
    }
    VectorXd y(dim);
    MatrixXd H(dim, 10);
    MatrixXd R = MatrixXd::Zero(dim, dim);
    for (std::size_t a = 0, row = 0; a < parts.size(); ++a) {
      const auto n = parts[a].innovation.size();
      y.segment(row, n) = parts[a].innovation;
      H.middleRows(row, n) = parts[a].jacobian;
      R.block(row, row, n, n) = parts[a].noise;
      for (std::size_t b = 0, col = 0; b < parts.size(); ++b) {
        const auto nb = parts[b].innovation.size();
        if (b != a && m.common_noise.size() > 0) R.block(row, col, n, nb) = m.common_noise;
        col += nb;
      }
      row += n;
    }
    const MatrixXd S = H * mode.P * H.transpose() + R;
    const Eigen::LDLT<MatrixXd> ldlt(S);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
      log_likelihood[j] = -std::numeric_limits<double>::infinity();
      continue;
    }
    const MatrixXd K = ldlt.solve(H * mode.P).transpose();  // P H^T S^-1 (S, P symmetric)
    mode.x += K * y;
    const MatrixXd IKH = Matrix10d::Identity() - K * H;
    mode.P = IKH * mode.P * IKH.transpose() + K * R * K.transpose();  // Joseph form
    mode.P = 0.5 * (mode.P + mode.P.transpose()).eval();
    log_likelihood[j] = -0.5 * (y.dot(ldlt.solve(y)) + ldlt.vectorD().array().log().sum() +
                                dim * std::log(2.0 * kPi));
  }
  if (track.imm.size() > 1) track.imm.UpdateProbabilities(log_likelihood);
  track.t_last_update_s = m.t_s;
  if (m.start) track.t_last_anchor_s = m.t_s;
  track_in = std::move(track);
  return static_cast<int>(accepted.size());
}

EkfEstimate Ekf::Combine(const Track& track, double t_s) const {
  const Imm10::Mode combined = track.imm.Combined();
  const Vector10d& x = combined.x;
  const Matrix10d& P = combined.P;
  EkfEstimate e;
  e.t_s = t_s;
  e.position_m = x.head<3>();
  e.velocity_mps = x.segment<3>(3);
  e.covariance = P.topLeftCorner<6, 6>();
  e.time_since_update_s = t_s - track.t_last_update_s;
  e.mode_probabilities = track.imm.probabilities();
  return e;
}

std::optional<EkfEstimate> Ekf::StateAt(double t_s) {
  AdvanceHorizon(t_s);
  Tracks tracks = committed_;
  for (const Measurement& m : buffer_) {
    if (m.t_s > t_s) break;
    Apply(tracks, m, nullptr);
  }
  Track& track = tracks.main;
  if (!track.confirmed) return std::nullopt;
  const double t_eff = std::min(t_s, track.t_last_update_s + config_.max_gap_s);
  if (t_eff >= track.t_s) {
    Predict(track, t_eff);
  } else {
    // Backwards: the means only, along each mode's own motion.
    const double dt = t_eff - track.t_s;
    for (std::size_t j = 0; j < track.imm.size(); ++j) {
      Vector10d& x = track.imm.modes()[j].x;
      if (modes_[j].kind == ModeKind::kCt) {  // back along the circle
        Vector10d back;
        Matrix10d unused;
        CoordinatedTurn(x, dt, back, unused);
        x = back;
        continue;
      }
      const bool ca = modes_[j].kind == ModeKind::kCa;
      x.head<3>() += dt * x.segment<3>(3) + (ca ? 0.5 * dt * dt : 0.0) * x.segment<3>(6);
      if (ca) x.segment<3>(3) += dt * x.segment<3>(6);
    }
  }
  return Combine(track, t_s);
}

std::optional<Eigen::Vector3d> Ekf::EstimateAt(double t_s) {
  const std::optional<EkfEstimate> e = StateAt(t_s);
  if (!e) return std::nullopt;
  return e->position_m;
}

}  // namespace uavsim::pipeline
