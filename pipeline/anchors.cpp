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

void AnchorTracker::Reset() { held_ = {}, gated_ = {}; }

namespace {

// A held point's position and range at t_end: carried forward at the rate of
// its last two fixes when they give a plausible one (`moving`), else as last
// seen.
struct CarriedPoint {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double range_m = 0.0;
  bool moving = false;
};

}  // namespace

bool AnchorTracker::Consistent(Modality m, const GeometricAnchor& point) const {
  const Held& camera = held_[static_cast<int>(Modality::kCamera)];
  if (!camera.window || std::abs(point.t_s - camera.anchor.t_s) > kGateMaxAge_s) return false;
  const GeometricAnchor& r = camera.anchor;
  if (m == Modality::kLidar)
    return (point.origin_w - ProjectOntoRay(point.origin_w, r.origin_w, r.direction_w)).norm() <=
           kLidarGate_m;
  return (point.origin_w -
          RangeOnRay(point.sensor_w, point.range_m, point.origin_w, r.origin_w, r.direction_w))
             .norm() <= kRadarGate_m;
}

void AnchorTracker::Held::Take(std::int64_t k, const GeometricAnchor& a) {
  if (window) previous = anchor;
  window = k;
  anchor = a;
}

AnchorWindow AnchorTracker::Update(std::int64_t k,
                                   const std::array<GeometricAnchor, kModalityCount>& arrived) {
  const double t_end = static_cast<double>(k) * window_s_;
  // The camera first: this window's ray gates this window's points.
  const auto camera_index = static_cast<std::size_t>(Modality::kCamera);
  if (arrived[camera_index].kind != GeometricAnchor::Kind::kNone)
    held_[camera_index].Take(k, arrived[camera_index]);
  for (const Modality m : {Modality::kLidar, Modality::kRadar}) {
    const GeometricAnchor& a = arrived[static_cast<std::size_t>(m)];
    if (a.kind == GeometricAnchor::Kind::kNone) continue;
    held_[static_cast<std::size_t>(m)].Take(k, a);
    if (Consistent(m, a)) gated_[static_cast<std::size_t>(m) - 1].Take(k, a);
  }

  const Held& camera = held_[static_cast<int>(Modality::kCamera)];
  const Held& lidar = held_[static_cast<int>(Modality::kLidar)];
  const Held& radar = held_[static_cast<int>(Modality::kRadar)];
  // Anchors older than kMaxAge_s give no candidates.
  const auto usable = [&](const Held& h) {
    return h.window.has_value() && t_end - h.anchor.t_s <= kMaxAge_s;
  };
  const bool ray = usable(camera);
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
  if (ray) {
    const Eigen::Vector3d o = normalised(r.origin_w);
    w.ray = {1.0f,
             static_cast<float>(o.x()),
             static_cast<float>(o.y()),
             static_cast<float>(o.z()),
             static_cast<float>(r.direction_w.x()),
             static_cast<float>(r.direction_w.y()),
             static_cast<float>(r.direction_w.z())};
  }
  const auto carried = [&](const Held& h, double max_carry_s) {
    CarriedPoint c{h.anchor.origin_w, h.anchor.range_m, false};
    if (!h.window || !h.previous) return c;
    const double dt = h.anchor.t_s - h.previous->t_s;
    const Eigen::Vector3d v = (h.anchor.origin_w - h.previous->origin_w) / dt;
    const double range_rate = (h.anchor.range_m - h.previous->range_m) / dt;
    c.moving = dt >= kMinFixGap_s && dt <= kMaxFixGap_s && v.norm() <= kMaxSpeed_mps &&
               std::abs(range_rate) <= kMaxSpeed_mps;
    if (c.moving) {
      const double age = std::clamp(t_end - h.anchor.t_s, 0.0, max_carry_s);
      c.p += v * age;
      c.range_m += range_rate * age;
    }
    return c;
  };
  // Each ranging sensor's point as held, and its fixes consistent with the
  // camera's ray on (or at the range of) the held ray.
  std::array<bool, 2> moving{}, gated_moving{};
  for (const auto& [j, h] : {std::pair{0, &lidar}, std::pair{1, &radar}}) {
    const CarriedPoint c = carried(*h, kMaxCarry_s);
    moving[static_cast<std::size_t>(j)] = c.moving;
    candidate(j, usable(*h), c.p);
    const Held& g = gated_[static_cast<std::size_t>(j)];
    const CarriedPoint cg = carried(g, kMaxCarryOnRay_s);
    gated_moving[static_cast<std::size_t>(j)] = cg.moving;
    const bool valid = usable(g) && ray;
    candidate(2 + j, valid, ProjectOntoRay(cg.p, r.origin_w, r.direction_w));
    candidate(4 + j, valid,
              RangeOnRay(g.anchor.sensor_w, cg.range_m, cg.p, r.origin_w, r.direction_w));
  }
  for (int i = 0; i < kAnchorCandidates; ++i) {
    w.features[static_cast<std::size_t>(f++)] = w.valid[static_cast<std::size_t>(i)];
    for (int c = 0; c < 3; ++c)
      w.features[static_cast<std::size_t>(f++)] =
          static_cast<float>(w.candidates[static_cast<std::size_t>(i)][c]);
  }
  // Capture to the end of window k, the time the estimate is for.
  const auto age = [&](const Held& h) {
    return h.window ? std::max(0.0, t_end - h.anchor.t_s) : kMaxAge_s;
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
  for (double unit : {kMaxAge_s, kFineAge_s})
    for (const Held& h : gated_)
      w.features[static_cast<std::size_t>(f++)] = static_cast<float>(std::min(age(h) / unit, 1.0));
  for (bool m : gated_moving) w.features[static_cast<std::size_t>(f++)] = m ? 1.0f : 0.0f;
  if (f != kAnchorFeatures)
    throw std::logic_error("AnchorTracker: wrote " + std::to_string(f) + " features");
  return w;
}

}  // namespace uavsim::pipeline
