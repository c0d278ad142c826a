#include "pipeline/anchored/geometric_anchor.h"

#include <algorithm>
#include <cmath>

namespace uavsim::pipeline {

GeometricAnchor AnchorOf(const CameraObservation& obs) {
  GeometricAnchor a;
  if (!obs.detected || !obs.bearing_left_w.allFinite() || obs.bearing_left_w.norm() < 1e-9)
    return a;
  a.kind = GeometricAnchor::Kind::kRay;
  a.t_s = obs.t_s;
  a.origin_w = obs.eye_left_w;
  a.direction_w = obs.bearing_left_w.normalized();
  return a;
}

GeometricAnchor AnchorOf(const PointObservation& obs) {
  GeometricAnchor a;
  const std::size_t n = obs.count();
  if (n == 0 || obs.channels < 3) return a;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double range_sum = 0.0, rate_sum = 0.0;
  const bool radar = obs.channels == 5;  // x, y, z, radial velocity, SNR
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = obs.values.data() + i * static_cast<std::size_t>(obs.channels);
    const Eigen::Vector3d q(p[0], p[1], p[2]);
    sum += q;
    range_sum += (q - obs.sensor_position_w).norm();
    if (radar) rate_sum += p[3];
  }
  a.has_range_rate = radar;
  a.range_rate_mps = radar ? rate_sum / static_cast<double>(n) : 0.0;
  a.kind = GeometricAnchor::Kind::kPoint;
  a.t_s = obs.t_s;
  a.origin_w = sum / static_cast<double>(n);
  a.sensor_w = obs.sensor_position_w;
  a.range_m = range_sum / static_cast<double>(n);
  return a;
}

std::uint32_t AnchorBytes(Modality m) {
  return m == Modality::kCamera ? 24 : m == Modality::kRadar ? 20 : 16;
}

Eigen::Vector3d ProjectOntoRay(const Eigen::Vector3d& p, const Eigen::Vector3d& o,
                               const Eigen::Vector3d& d) {
  return o + std::max(1.0, (p - o).dot(d)) * d;
}

Eigen::Vector3d RangeOnRay(const Eigen::Vector3d& sensor, double range, const Eigen::Vector3d& hint,
                           const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  // |o + t d - sensor|^2 = range^2: t^2 + 2 b t + c = 0.
  const Eigen::Vector3d os = o - sensor;
  const double b = os.dot(d);
  const double c = os.squaredNorm() - range * range;
  const double disc = b * b - c;
  double t = -b;
  if (disc >= 0.0) {
    const double root = std::sqrt(disc);
    const double t1 = -b - root, t2 = -b + root;
    t = (o + t1 * d - hint).squaredNorm() <= (o + t2 * d - hint).squaredNorm() ? t1 : t2;
  }
  return o + std::max(1.0, t) * d;
}

bool AnchorAgreesWithRay(Modality m, const GeometricAnchor& point, const GeometricAnchor& r) {
  if (std::abs(point.t_s - r.t_s) > RayGate::kGateMaxAge_s) return false;
  if (m == Modality::kLidar)
    return (point.origin_w - ProjectOntoRay(point.origin_w, r.origin_w, r.direction_w)).norm() <=
           RayGate::kLidarGate_m;
  return (point.origin_w -
          RangeOnRay(point.sensor_w, point.range_m, point.origin_w, r.origin_w, r.direction_w))
             .norm() <= RayGate::kRadarGate_m;
}

}  // namespace uavsim::pipeline
