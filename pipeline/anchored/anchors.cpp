#include "pipeline/anchored/anchors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace uavsim::pipeline {

AnchorTracker::AnchorTracker(double window_s, const Eigen::Vector3d& centre_m, double scale_m)
    : window_s_(window_s), centre_m_(centre_m), scale_m_(scale_m) {
  if (!std::isfinite(window_s) || window_s <= 0.0 || !std::isfinite(scale_m) || scale_m <= 0.0)
    throw std::invalid_argument("AnchorTracker: window_s and scale_m must be finite and > 0");
}

void AnchorTracker::Reset() { held_ = {}, gated_ = {}, filter_.Reset(); }

void AnchorTracker::Held::Take(std::int64_t k, const GeometricAnchor& a) {
  if (window) previous = anchor;
  window = k;
  anchor = a;
}

AnchorWindow AnchorTracker::Update(std::int64_t k,
                                   const std::array<GeometricAnchor, kModalityCount>& arrived) {
  WindowAnchors all;
  for (std::size_t m = 0; m < all.size(); ++m)
    if (arrived[m].kind != GeometricAnchor::Kind::kNone) all[m].push_back(arrived[m]);
  return Update(k, all);
}

AnchorWindow AnchorTracker::Update(std::int64_t k, const WindowAnchors& all) {
  // The filter: every anchor in capture order (the camera first at a tie).
  filter_.ObserveWindow(all);
  TakeArrivals(k, all);
  const double t_end = static_cast<double>(k) * window_s_;
  AnchorWindow w;
  Moving moving{}, gated_moving{};
  WriteCandidates(t_end, w, moving, gated_moving);
  int f = 0;
  for (int i = 0; i < kFilterCandidate; ++i) {
    w.features[static_cast<std::size_t>(f++)] = w.valid[static_cast<std::size_t>(i)];
    for (int c = 0; c < 3; ++c)
      w.features[static_cast<std::size_t>(f++)] =
          static_cast<float>(w.candidates[static_cast<std::size_t>(i)][c]);
  }
  f = WriteHeldFeatures(k, t_end, moving, gated_moving, w, f);
  f = WriteTrackFeatures(t_end, w, f);
  if (f != kAnchorFeatures)
    throw std::logic_error("AnchorTracker: wrote " + std::to_string(f) + " features");
  return w;
}

void AnchorTracker::TakeArrivals(std::int64_t k, const WindowAnchors& all) {
  std::array<GeometricAnchor, kModalityCount> arrived;
  for (std::size_t m = 0; m < all.size(); ++m)
    for (const GeometricAnchor& a : all[m])
      if (a.kind != GeometricAnchor::Kind::kNone &&
          (arrived[m].kind == GeometricAnchor::Kind::kNone || a.t_s >= arrived[m].t_s))
        arrived[m] = a;
  // The camera first: this window's ray gates this window's points.
  const auto camera_index = static_cast<std::size_t>(Modality::kCamera);
  if (arrived[camera_index].kind != GeometricAnchor::Kind::kNone)
    held_[camera_index].Take(k, arrived[camera_index]);
  for (const Modality m : {Modality::kLidar, Modality::kRadar}) {
    const GeometricAnchor& a = arrived[static_cast<std::size_t>(m)];
    if (a.kind == GeometricAnchor::Kind::kNone) continue;
    held_[static_cast<std::size_t>(m)].Take(k, a);
    const Held& camera = held_[camera_index];
    if (camera.window && AnchorAgreesWithRay(m, a, camera.anchor))
      gated_[static_cast<std::size_t>(m) - 1].Take(k, a);
  }
}

// Anchors older than kMaxAge_s give no candidates.
bool AnchorTracker::Usable(const Held& h, double t_end) const {
  return h.window.has_value() && t_end - h.anchor.t_s <= kMaxAge_s;
}

double AnchorTracker::Age(const Held& h, double t_end) const {
  return h.window ? std::max(0.0, t_end - h.anchor.t_s) : kMaxAge_s;
}

Eigen::Vector3d AnchorTracker::Normalised(const Eigen::Vector3d& p) const {
  return (p - centre_m_) / scale_m_;
}

void AnchorTracker::SetCandidate(AnchorWindow& w, int i, bool valid,
                                 const Eigen::Vector3d& p_w) const {
  w.valid[static_cast<std::size_t>(i)] = valid ? 1.0f : 0.0f;
  w.candidates[static_cast<std::size_t>(i)] = valid ? Normalised(p_w) : Eigen::Vector3d::Zero();
}

AnchorTracker::CarriedPoint AnchorTracker::Carry(const Held& h, double t_end, double max_carry_s) {
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
}

void AnchorTracker::WriteCandidates(double t_end, AnchorWindow& w, Moving& moving,
                                    Moving& gated_moving) const {
  const Held& camera = held_[static_cast<int>(Modality::kCamera)];
  const Held& lidar = held_[static_cast<int>(Modality::kLidar)];
  const Held& radar = held_[static_cast<int>(Modality::kRadar)];
  const bool ray = Usable(camera, t_end);
  const GeometricAnchor& r = camera.anchor;
  if (ray) {
    const Eigen::Vector3d o = Normalised(r.origin_w);
    w.ray = {1.0f,
             static_cast<float>(o.x()),
             static_cast<float>(o.y()),
             static_cast<float>(o.z()),
             static_cast<float>(r.direction_w.x()),
             static_cast<float>(r.direction_w.y()),
             static_cast<float>(r.direction_w.z())};
  }
  // Each ranging sensor's point as held, and its fixes consistent with the
  // camera's ray on (or at the range of) the held ray.
  for (const auto& [j, h] : {std::pair{0, &lidar}, std::pair{1, &radar}}) {
    const CarriedPoint c = Carry(*h, t_end, kMaxCarry_s);
    moving[static_cast<std::size_t>(j)] = c.moving;
    SetCandidate(w, j, Usable(*h, t_end), c.p);
    const Held& g = gated_[static_cast<std::size_t>(j)];
    const CarriedPoint cg = Carry(g, t_end, kMaxCarryOnRay_s);
    gated_moving[static_cast<std::size_t>(j)] = cg.moving;
    const bool valid = Usable(g, t_end) && ray;
    SetCandidate(w, 2 + j, valid, ProjectOntoRay(cg.p, r.origin_w, r.direction_w));
    SetCandidate(w, 4 + j, valid,
                 RangeOnRay(g.anchor.sensor_w, cg.range_m, cg.p, r.origin_w, r.direction_w));
  }
}

int AnchorTracker::WriteHeldFeatures(std::int64_t k, double t_end, const Moving& moving,
                                     const Moving& gated_moving, AnchorWindow& w, int f) const {
  const Held& camera = held_[static_cast<int>(Modality::kCamera)];
  const Held& lidar = held_[static_cast<int>(Modality::kLidar)];
  const Held& radar = held_[static_cast<int>(Modality::kRadar)];
  const bool ray = Usable(camera, t_end);
  const GeometricAnchor& r = camera.anchor;
  // Capture to the end of window k, the time the estimate is for.
  for (double unit : {kMaxAge_s, kFineAge_s})
    for (const Held& h : held_)
      w.features[static_cast<std::size_t>(f++)] =
          static_cast<float>(std::min(Age(h, t_end) / unit, 1.0));
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
      w.features[static_cast<std::size_t>(f++)] =
          static_cast<float>(std::min(Age(h, t_end) / unit, 1.0));
  for (bool m : gated_moving) w.features[static_cast<std::size_t>(f++)] = m ? 1.0f : 0.0f;
  return f;
}

int AnchorTracker::WriteTrackFeatures(double t_end, AnchorWindow& w, int f) const {
  const std::optional<AnchorFilter::Estimate> track = filter_.PredictAt(t_end);
  SetCandidate(w, kFilterCandidate, track.has_value(),
               track ? track->position_m : Eigen::Vector3d::Zero());
  w.features[static_cast<std::size_t>(f++)] = track ? 1.0f : 0.0f;
  for (int c = 0; c < 3; ++c)
    w.features[static_cast<std::size_t>(f++)] =
        static_cast<float>(w.candidates[static_cast<std::size_t>(kFilterCandidate)][c]);
  w.features[static_cast<std::size_t>(f++)] =
      track ? static_cast<float>(std::min(track->sigma_m / kSigmaUnit_m, 4.0)) : 4.0f;
  for (double unit : {kMaxAge_s, kFineAge_s})
    w.features[static_cast<std::size_t>(f++)] =
        track ? static_cast<float>(std::min(track->ranging_age_s / unit, 1.0)) : 1.0f;
  return f;
}

std::array<Eigen::Vector3d, kAnchorCandidates> MedianCandidateOffsets(
    const std::vector<AnchorWindow>& windows, const std::vector<Eigen::Vector3d>& truth,
    double scale_m, double radius_m, std::size_t min_windows) {
  if (windows.size() != truth.size())
    throw std::invalid_argument("MedianCandidateOffsets: " + std::to_string(windows.size()) +
                                " windows but " + std::to_string(truth.size()) + " truths");
  if (!(std::isfinite(scale_m) && scale_m > 0.0 && std::isfinite(radius_m) && radius_m > 0.0))
    throw std::invalid_argument(
        "MedianCandidateOffsets: scale_m and radius_m must be finite and > 0");
  std::array<Eigen::Vector3d, kAnchorCandidates> offsets;
  for (int c = 0; c < kAnchorCandidates; ++c) {
    const auto ci = static_cast<std::size_t>(c);
    std::array<std::vector<double>, 3> axes;
    for (std::size_t i = 0; i < windows.size(); ++i) {
      if (windows[i].valid[ci] < 0.5f) continue;
      const Eigen::Vector3d d = scale_m * (windows[i].candidates[ci] - truth[i]);
      if (!(d.norm() <= radius_m)) continue;
      for (int j = 0; j < 3; ++j) axes[static_cast<std::size_t>(j)].push_back(d[j]);
    }
    offsets[ci].setZero();
    const std::size_t n = axes[0].size();
    if (n == 0 || n < min_windows) continue;
    for (int j = 0; j < 3; ++j) {
      std::vector<double>& a = axes[static_cast<std::size_t>(j)];
      std::sort(a.begin(), a.end());
      offsets[ci][j] = n % 2 ? a[n / 2] : 0.5 * (a[n / 2 - 1] + a[n / 2]);
    }
  }
  return offsets;
}

}  // namespace uavsim::pipeline
