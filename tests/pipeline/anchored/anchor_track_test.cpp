// `anchor_track` (pipeline/anchored/anchor_track.h): the anchor filter alone
// as a method. A target flying a straight line at constant velocity seen by
// a camera ray at 30 Hz and a LiDAR at 10 Hz: nothing before the track is
// confirmed, then the analytic trajectory; the last estimate held once the
// filter stops predicting; the same track the anchored model's tracker
// offers as its filter candidate (anchors.h); windows out of order refused.
#include "pipeline/anchored/anchor_track.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>

#include "pipeline/anchored/anchors.h"

namespace uavsim::pipeline {
namespace {

constexpr double kWindow = 0.2;
const Eigen::Vector3d kEye(-30.0, -20.0, 1.5);

// The target: straight and level at 4 m/s along x.
Eigen::Vector3d Truth(double t) { return {-10.0 + 4.0 * t, 5.0, 30.0}; }

GeometricAnchor RayAt(double t) {
  GeometricAnchor a;
  a.kind = GeometricAnchor::Kind::kRay;
  a.origin_w = kEye;
  a.direction_w = (Truth(t) - kEye).normalized();
  a.t_s = t;
  return a;
}

GeometricAnchor LidarAt(double t) {
  GeometricAnchor a;
  a.kind = GeometricAnchor::Kind::kPoint;
  a.origin_w = Truth(t);
  a.sensor_w = {20.0, -20.0, 1.0};
  a.range_m = (Truth(t) - a.sensor_w).norm();
  a.t_s = t;
  return a;
}

// Window k's anchors: camera frames at (i + 0.5) / 30 s, LiDAR scans at
// (i + 0.5) / 10 s from `lidar_from_s` to `lidar_until_s`, rays until
// `rays_until_s`.
WindowAnchors Window(std::int64_t k, double lidar_from_s, double lidar_until_s,
                     double rays_until_s) {
  WindowAnchors w;
  const double t0 = (k - 1) * kWindow, t1 = k * kWindow;
  for (int i = 0; (i + 0.5) / 30.0 < t1; ++i)
    if (const double t = (i + 0.5) / 30.0; t >= t0 && t < rays_until_s)
      w[static_cast<int>(Modality::kCamera)].push_back(RayAt(t));
  for (int i = 0; (i + 0.5) / 10.0 < t1; ++i)
    if (const double t = (i + 0.5) / 10.0; t >= t0 && t >= lidar_from_s && t < lidar_until_s)
      w[static_cast<int>(Modality::kLidar)].push_back(LidarAt(t));
  return w;
}

}  // namespace

TEST_CASE("AnchorTrack: silent until confirmed, then the target's straight line", "[pipeline]") {
  AnchorTrack track(kWindow);
  // Rays alone fix no range: no track, no answer.
  for (std::int64_t k = 1; k <= 5; ++k) CHECK_FALSE(track.OnWindow(k, Window(k, 1.0, 1e9, 1e9)));
  // LiDAR from 1 s: the first fix starts a track of unknown velocity
  // (sigma_v 6 m/s per axis puts it above 1 m at the window's end), so the
  // first windows with LiDAR may still be silent; it answers within 1 s.
  std::optional<std::int64_t> first;
  for (std::int64_t k = 6; k <= 60; ++k) {
    const auto p = track.OnWindow(k, Window(k, 1.0, 1e9, 1e9));
    if (p && !first) first = k;
    if (first) REQUIRE(p.has_value());  // once answering, always
    // From 3 s on the estimate is the truth at the window's end: noiseless
    // fixes of a constant-velocity target (tolerance: the IMM's turn mode
    // and the start's velocity prior have decayed to this).
    if (k >= 15) {
      INFO("window " << k << ": (" << p->transpose() << ") vs (" << Truth(k * kWindow).transpose()
                     << ")");
      CHECK((*p - Truth(k * kWindow)).norm() < 0.05);
    }
  }
  REQUIRE(first.has_value());
  CHECK(*first >= 6);
  CHECK(*first <= 10);
}

TEST_CASE("AnchorTrack: holds its last estimate once the filter stops predicting", "[pipeline]") {
  AnchorTrack track(kWindow);
  // LiDAR and rays until 4 s, then nothing.
  std::optional<Eigen::Vector3d> p;
  for (std::int64_t k = 1; k <= 20; ++k) p = track.OnWindow(k, Window(k, 0.0, 4.0, 4.0));
  REQUIRE(p.has_value());
  // Predicted on along the line while the filter predicts (kMaxPredict_s
  // after the last fix at 3.95 s) ...
  const double stop = 3.95 + AnchorFilter::kMaxPredict_s;
  std::optional<Eigen::Vector3d> last_predicted;
  for (std::int64_t k = 21; k * kWindow < stop - 1e-9; ++k) {
    last_predicted = track.OnWindow(k, {});
    REQUIRE(last_predicted.has_value());
    CHECK((*last_predicted - Truth(k * kWindow)).norm() < 0.05);
  }
  REQUIRE(last_predicted.has_value());
  // ... then held where it last was.
  for (std::int64_t k = static_cast<std::int64_t>(std::ceil(stop / kWindow)) + 1; k < 60; ++k) {
    const auto held = track.OnWindow(k, {});
    REQUIRE(held.has_value());
    CHECK(*held == *last_predicted);
  }
  // Reset forgets everything.
  track.Reset();
  CHECK_FALSE(track.OnWindow(1, Window(1, 1.0, 1e9, 1e9)));
}

TEST_CASE("AnchorTrack: the anchored model's filter candidate, window by window", "[pipeline]") {
  const Eigen::Vector3d centre(0.0, 0.0, 25.0);
  const double scale = 15.0;
  AnchorTrack track(kWindow);
  AnchorTracker tracker(kWindow, centre, scale);
  int compared = 0;
  for (std::int64_t k = 1; k <= 40; ++k) {
    const WindowAnchors w = Window(k, 1.0, 6.0, 1e9);
    const auto p = track.OnWindow(k, w);
    const AnchorWindow a = tracker.Update(k, w);
    if (!p) continue;
    REQUIRE(a.valid[kFilterCandidate] > 0.5f);
    const Eigen::Vector3d candidate = centre + scale * a.candidates[kFilterCandidate];
    INFO("window " << k);
    CHECK((candidate - *p).norm() < 1e-9);
    ++compared;
  }
  CHECK(compared > 20);
}

TEST_CASE("AnchorTrack: refuses windows out of order and a bad window length", "[pipeline]") {
  AnchorTrack track(kWindow);
  track.OnWindow(3, {});
  CHECK_THROWS_AS(track.OnWindow(3, {}), std::invalid_argument);
  CHECK_THROWS_AS(track.OnWindow(2, {}), std::invalid_argument);
  CHECK_NOTHROW(track.OnWindow(7, {}));  // skipped windows are empty
  CHECK_THROWS_AS(AnchorTrack(0.0), std::invalid_argument);
  CHECK_THROWS_AS(AnchorTrack(std::nan("")), std::invalid_argument);
}

}  // namespace uavsim::pipeline
