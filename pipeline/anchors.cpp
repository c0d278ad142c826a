#include "pipeline/anchors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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
  double range_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = obs.values.data() + i * static_cast<std::size_t>(obs.channels);
    const Eigen::Vector3d q(p[0], p[1], p[2]);
    sum += q;
    range_sum += (q - obs.sensor_position_w).norm();
  }
  a.kind = GeometricAnchor::Kind::kPoint;
  a.t_s = obs.t_s;
  a.origin_w = sum / static_cast<double>(n);
  a.sensor_w = obs.sensor_position_w;
  a.range_m = range_sum / static_cast<double>(n);
  return a;
}

std::uint32_t AnchorBytes(Modality m) { return m == Modality::kCamera ? 24 : 16; }

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

AnchorTracker::AnchorTracker(double window_s, const Eigen::Vector3d& centre_m, double scale_m)
    : window_s_(window_s), centre_m_(centre_m), scale_m_(scale_m) {
  if (!std::isfinite(window_s) || window_s <= 0.0 || !std::isfinite(scale_m) || scale_m <= 0.0)
    throw std::invalid_argument("AnchorTracker: window_s and scale_m must be finite and > 0");
}

void AnchorTracker::Reset() { held_ = {}; }

AnchorWindow AnchorTracker::Update(std::int64_t k,
                                   const std::array<GeometricAnchor, kModalityCount>& arrived) {
  for (int m = 0; m < kModalityCount; ++m)
    if (arrived[static_cast<std::size_t>(m)].kind != GeometricAnchor::Kind::kNone) {
      Held& h = held_[static_cast<std::size_t>(m)];
      if (h.window) h.previous = h.anchor;
      h.window = k;
      h.anchor = arrived[static_cast<std::size_t>(m)];
    }

  const Held& camera = held_[static_cast<int>(Modality::kCamera)];
  const Held& lidar = held_[static_cast<int>(Modality::kLidar)];
  const Held& radar = held_[static_cast<int>(Modality::kRadar)];
  const bool ray = camera.window.has_value();
  const auto normalised = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return (p - centre_m_) / scale_m_;
  };

  AnchorWindow w;
  int f = 0;
  const auto candidate = [&](int i, bool valid, const Eigen::Vector3d& p_w) {
    w.valid[static_cast<std::size_t>(i)] = valid ? 1.0f : 0.0f;
    w.candidates[static_cast<std::size_t>(i)] = valid ? normalised(p_w) : Eigen::Vector3d::Zero();
  };
  const GeometricAnchor& r = camera.anchor;
  // Each ranging sensor's point and range at the end of window k: carried
  // forward at the rate of its last two fixes when they give a plausible
  // one, else as last seen.
  const double t_end = static_cast<double>(k) * window_s_;
  std::array<bool, 2> moving{};
  for (const auto& [j, h] : {std::pair{0, &lidar}, std::pair{1, &radar}}) {
    Eigen::Vector3d p = h->anchor.origin_w;
    double range = h->anchor.range_m;
    if (h->window && h->previous) {
      const double dt = h->anchor.t_s - h->previous->t_s;
      const Eigen::Vector3d v = (h->anchor.origin_w - h->previous->origin_w) / dt;
      moving[j] = dt >= kMinFixGap_s && dt <= kMaxFixGap_s && v.norm() <= kMaxSpeed_mps;
      if (moving[j]) {
        const double age = std::max(0.0, t_end - h->anchor.t_s);
        p += v * age;
        range += (h->anchor.range_m - h->previous->range_m) / dt * age;
      }
    }
    const bool seen = h->window.has_value();
    candidate(j, seen, p);
    candidate(2 + j, seen && ray, ProjectOntoRay(p, r.origin_w, r.direction_w));
    candidate(4 + j, seen && ray,
              RangeOnRay(h->anchor.sensor_w, range, p, r.origin_w, r.direction_w));
  }
  for (int i = 0; i < kAnchorCandidates; ++i) {
    w.features[static_cast<std::size_t>(f++)] = w.valid[static_cast<std::size_t>(i)];
    for (int c = 0; c < 3; ++c)
      w.features[static_cast<std::size_t>(f++)] =
          static_cast<float>(w.candidates[static_cast<std::size_t>(i)][c]);
  }
  // Capture to the end of window k, the time the estimate is for.
  const auto age = [&](const Held& h) {
    return h.window ? std::max(0.0, static_cast<double>(k) * window_s_ - h.anchor.t_s) : kMaxAge_s;
  };
  for (double unit : {kMaxAge_s, kFineAge_s})
    for (const Held& h : held_)
      w.features[static_cast<std::size_t>(f++)] = static_cast<float>(std::min(age(h) / unit, 1.0));
  for (const Held& h : held_)
    w.features[static_cast<std::size_t>(f++)] = h.window && *h.window == k ? 1.0f : 0.0f;
  for (bool m : moving) w.features[static_cast<std::size_t>(f++)] = m ? 1.0f : 0.0f;
  for (const Held* h : {&lidar, &radar}) {
    double d = 0.0;
    if (ray && h->window)
      d = (h->anchor.origin_w - ProjectOntoRay(h->anchor.origin_w, r.origin_w, r.direction_w))
              .norm();
    w.features[static_cast<std::size_t>(f++)] =
        static_cast<float>(std::min(d / kRayDistanceUnit_m, 4.0));
  }
  const double lr =
      lidar.window && radar.window ? (lidar.anchor.origin_w - radar.anchor.origin_w).norm() : 0.0;
  w.features[static_cast<std::size_t>(f++)] = static_cast<float>(std::min(lr / scale_m_, 4.0));
  for (int c = 0; c < 3; ++c)
    w.features[static_cast<std::size_t>(f++)] = ray ? static_cast<float>(r.direction_w[c]) : 0.0f;
  if (f != kAnchorFeatures)
    throw std::logic_error("AnchorTracker: wrote " + std::to_string(f) + " features");
  return w;
}

}  // namespace uavsim::pipeline
