// Geometric anchors (pipeline/anchored/anchors.h): a node's anchor against its closed
// form (centroid, ray), the projection onto a ray, the edge's tracker of held
// anchors window by window (candidates, the gate against the camera's ray and
// the 54 features worked out by hand), and TE-Align's list of a window's
// anchors.
#include "pipeline/anchored/anchors.h"

#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "pipeline/edge/te_align.h"

namespace uavsim::pipeline {
namespace {

using Kind = GeometricAnchor::Kind;

constexpr std::size_t kCamera = static_cast<std::size_t>(Modality::kCamera);
constexpr std::size_t kLidar = static_cast<std::size_t>(Modality::kLidar);
constexpr std::size_t kRadar = static_cast<std::size_t>(Modality::kRadar);

// Feature offsets (see kAnchorFeatures).
constexpr std::size_t kAgeOffset = 24;  // 3 coarse (/ 5 s), then 3 fine (/ 1 s)
constexpr std::size_t kFreshOffset = 30;
constexpr std::size_t kMovingOffset = 33;
constexpr std::size_t kRayDistanceOffset = 35;
constexpr std::size_t kLidarRadarOffset = 37;
constexpr std::size_t kDirectionOffset = 38;
constexpr std::size_t kGatedAgeOffset = 41;  // LiDAR, radar coarse, then fine
constexpr std::size_t kGatedMovingOffset = 45;

GeometricAnchor Point(double x, double y, double z, double t_s = 0.0) {
  GeometricAnchor a;
  a.kind = Kind::kPoint;
  a.origin_w = {x, y, z};
  a.t_s = t_s;
  return a;
}

GeometricAnchor Ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                    double t_s = 0.0) {
  GeometricAnchor a;
  a.kind = Kind::kRay;
  a.origin_w = origin;
  a.direction_w = direction.normalized();
  a.t_s = t_s;
  return a;
}

void CheckVector(const Eigen::Vector3d& got, const Eigen::Vector3d& expected, double tol = 1e-12) {
  INFO("got (" << got.transpose() << "), expected (" << expected.transpose() << ")");
  CHECK((got - expected).norm() <= tol);
}

// Candidate i's valid flag and position in both the candidates and the
// features [valid, x, y, z].
void CheckCandidate(const AnchorWindow& w, int i, bool valid,
                    const Eigen::Vector3d& expected = Eigen::Vector3d::Zero()) {
  INFO("candidate " << i);
  const auto u = static_cast<std::size_t>(i);
  const std::size_t offset = i == kFilterCandidate ? kFilterFeatureOffset : 4 * u;
  CHECK(w.valid[u] == (valid ? 1.0f : 0.0f));
  CHECK(w.features[offset] == (valid ? 1.0f : 0.0f));
  if (!valid) return;
  CheckVector(w.candidates[u], expected);
  for (int c = 0; c < 3; ++c)
    CHECK(w.features[offset + 1 + static_cast<std::size_t>(c)] == Approx(expected[c]).margin(1e-6));
}

void CheckFeatures(const AnchorWindow& w, std::size_t offset, const std::vector<double>& expected) {
  for (std::size_t i = 0; i < expected.size(); ++i) {
    INFO("feature " << offset + i);
    CHECK(w.features[offset + i] == Approx(expected[i]).margin(1e-6));
  }
}

// A tracker holding nothing: no candidate, saturated ages, nothing fresh.
void CheckNothingHeld(const AnchorWindow& w) {
  for (int i = 0; i < kAnchorCandidates; ++i) CheckCandidate(w, i, false);
  CheckFeatures(w, 0, std::vector<double>(24, 0.0));
  CheckFeatures(w, kAgeOffset,
                {1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0});
  CheckFeatures(w, kGatedAgeOffset, {1.0, 1.0, 1.0, 1.0, 0.0, 0.0});
  CheckFeatures(w, kFilterFeatureOffset, {0.0, 0.0, 0.0, 0.0, 4.0, 1.0, 1.0});
}

// The held ray the tracker hands the head: valid, origin, direction.
void CheckRay(const AnchorWindow& w, const std::array<float, 7>& expected) {
  for (std::size_t i = 0; i < 7; ++i) CHECK(w.ray[i] == Approx(expected[i]).margin(1e-7));
}

LatentFrame Frame(double t_s, const GeometricAnchor& anchor) {
  LatentFrame f;
  f.t_s = t_s;
  f.latent.assign(4, 0.5f);
  f.anchor = anchor;
  return f;
}

}  // namespace

TEST_CASE("AnchorOf: a point cloud's anchor is the mean of its points", "[pipeline]") {
  PointObservation lidar;
  lidar.channels = 4;  // x, y, z, intensity
  lidar.values = {1, 2, 3, 100, 4, 5, 6, 200, 7, -8, 0, 50};
  lidar.sensor_position_w = {1, 2, -1};
  lidar.t_s = 2.5;
  const GeometricAnchor l = AnchorOf(lidar);
  CHECK(l.kind == Kind::kPoint);
  CHECK(l.t_s == 2.5);
  // ((1 + 4 + 7) / 3, (2 + 5 - 8) / 3, (3 + 6 + 0) / 3)
  CheckVector(l.origin_w, {4.0, -1.0 / 3.0, 3.0}, 1e-6);
  // The sensor and the mean range: |(0, 0, 4)| = 4, |(3, 3, 7)| = sqrt(67),
  // |(6, -10, 1)| = sqrt(137).
  CheckVector(l.sensor_w, {1.0, 2.0, -1.0});
  CHECK(l.range_m == Approx((4.0 + std::sqrt(67.0) + std::sqrt(137.0)) / 3.0).epsilon(1e-9));

  PointObservation radar;
  radar.channels = 5;  // x, y, z, radial velocity, SNR
  radar.values = {10, 0, 0, -3, 20, 0, 10, 0, 4, 25, 0, 0, 10, 1, 30, 2, 2, 2, 0, 15};
  const GeometricAnchor r = AnchorOf(radar);
  CHECK(r.kind == Kind::kPoint);
  CheckVector(r.origin_w, {3.0, 3.0, 3.0}, 1e-6);  // (12, 12, 12) / 4
  CHECK(r.has_range_rate);
  CHECK(r.range_rate_mps == Approx(0.5));  // (-3 + 4 + 1 + 0) / 4
  CHECK_FALSE(l.has_range_rate);           // LiDAR: 4 channels

  PointObservation one;
  one.channels = 5;
  one.values = {-1.5f, 2.25f, 40.0f, 0.0f, 10.0f};
  CheckVector(AnchorOf(one).origin_w, {-1.5, 2.25, 40.0});

  PointObservation empty;
  empty.channels = 4;
  CHECK(AnchorOf(empty).kind == Kind::kNone);
  empty.channels = 5;
  CHECK(AnchorOf(empty).kind == Kind::kNone);
}

TEST_CASE("AnchorOf: a camera's anchor is the left eye's ray, none when undetected", "[pipeline]") {
  CameraObservation cam;
  cam.detected = true;
  cam.eye_left_w = {1.0, 2.0, 3.0};
  cam.eye_right_w = {1.5, 2.0, 3.0};
  cam.bearing_left_w = {0.0, 3.0, 4.0};  // length 5
  cam.bearing_right_w = {1.0, 0.0, 0.0};
  cam.t_s = 0.7;
  const GeometricAnchor a = AnchorOf(cam);
  CHECK(a.kind == Kind::kRay);
  CHECK(a.t_s == 0.7);
  CheckVector(a.origin_w, {1.0, 2.0, 3.0});
  CheckVector(a.direction_w, {0.0, 0.6, 0.8});

  cam.bearing_left_w = {-2.0, 1.0, 2.0};  // length 3
  CheckVector(AnchorOf(cam).direction_w, {-2.0 / 3.0, 1.0 / 3.0, 2.0 / 3.0});

  cam.detected = false;
  CHECK(AnchorOf(cam).kind == Kind::kNone);
  CHECK(AnchorOf(CameraObservation{}).kind == Kind::kNone);

  // A degenerate bearing gives no ray rather than a NaN direction.
  cam.detected = true;
  cam.bearing_left_w = Eigen::Vector3d::Zero();
  CHECK(AnchorOf(cam).kind == Kind::kNone);
}

TEST_CASE("AnchorBytes: 24 bytes for the camera's ray, 16 for a point and its range, 20 radar",
          "[pipeline]") {
  CHECK(AnchorBytes(Modality::kCamera) == 24);
  CHECK(AnchorBytes(Modality::kLidar) == 16);
  CHECK(AnchorBytes(Modality::kRadar) == 20);  // and its radial velocity
}

TEST_CASE("ProjectOntoRay: the foot of the perpendicular, at least 1 m ahead", "[pipeline]") {
  const Eigen::Vector3d o(1.0, 2.0, 3.0);
  // Along x: the foot of (7, 5, -1) is (7, 2, 3).
  CheckVector(ProjectOntoRay({7.0, 5.0, -1.0}, o, Eigen::Vector3d::UnitX()), {7.0, 2.0, 3.0});
  // Along (0, 0.6, 0.8): p - o = (4, 5, 10), (p - o).d = 3 + 8 = 11, foot o + 11 d.
  const Eigen::Vector3d d(0.0, 0.6, 0.8);
  CheckVector(ProjectOntoRay({5.0, 7.0, 13.0}, o, d), {1.0, 2.0 + 6.6, 3.0 + 8.8});
  // A point on the ray is its own foot.
  CheckVector(ProjectOntoRay(o + 4.0 * d, o, d), o + 4.0 * d);
  // Behind the origin, at the origin or less than 1 m ahead: o + 1 d.
  CheckVector(ProjectOntoRay({-5.0, 0.0, 0.0}, o, Eigen::Vector3d::UnitX()), {2.0, 2.0, 3.0});
  CheckVector(ProjectOntoRay(o, o, d), o + d);
  CheckVector(ProjectOntoRay(o + 0.5 * d + Eigen::Vector3d(3.0, 0.0, 0.0), o, d), o + d);
  // Exactly 1 m ahead: both rules agree.
  CheckVector(ProjectOntoRay(o + d, o, d), o + d);
}

TEST_CASE("RangeOnRay: the ray's crossing of the range sphere nearer the hint", "[pipeline]") {
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  // Sensor (1, 2, 3), range 10, ray along x from the origin:
  // (t - 1)^2 + 13 = 100, t = 1 +- sqrt(87).
  const Eigen::Vector3d s(1.0, 2.0, 3.0);
  CheckVector(RangeOnRay(s, 10.0, {11.0, 2.0, 3.0}, o, x), {1.0 + std::sqrt(87.0), 0.0, 0.0},
              1e-12);
  // Sensor (20, 3, 0), range 5: t = 20 -+ 4; the hint picks the crossing.
  const Eigen::Vector3d s2(20.0, 3.0, 0.0);
  CheckVector(RangeOnRay(s2, 5.0, {15.0, 0.0, 0.0}, o, x), {16.0, 0.0, 0.0}, 1e-12);
  CheckVector(RangeOnRay(s2, 5.0, {25.0, 9.0, 0.0}, o, x), {24.0, 0.0, 0.0}, 1e-12);
  // A sphere the ray misses: the ray's point nearest the sensor.
  CheckVector(RangeOnRay(s2, 2.0, {0.0, 0.0, 0.0}, o, x), {20.0, 0.0, 0.0}, 1e-12);
  // Both crossings behind the origin: 1 m ahead.
  CheckVector(RangeOnRay({-20.0, 0.0, 0.0}, 5.0, {-20.0, 0.0, 0.0}, o, x), {1.0, 0.0, 0.0});
}

TEST_CASE("AnchorTracker: candidates and features window by window", "[pipeline]") {
  const Eigen::Vector3d centre(1.0, 2.0, 3.0);
  AnchorTracker tracker(0.2, centre, 10.0);

  SECTION("nothing seen yet") { CheckNothingHeld(tracker.Update(1, WindowAnchors{})); }

  SECTION("a LiDAR point, then a camera ray and a radar point, then nothing") {
    // Window 1 [0, 0.2): only a LiDAR point, 10 m east of the centre, seen
    // from the centre at t = 0.1 s.
    PointObservation lidar;
    lidar.channels = 4;
    lidar.values = {11, 2, 3, 1};
    lidar.sensor_position_w = centre;
    lidar.t_s = 0.1;
    std::array<GeometricAnchor, kModalityCount> arrived;
    arrived[kLidar] = AnchorOf(lidar);
    const AnchorWindow w1 = tracker.Update(1, arrived);
    CheckCandidate(w1, 0, true, {1.0, 0.0, 0.0});
    for (int i = 1; i < kAnchorCandidates; ++i) {
      CheckCandidate(w1, i, false);
      CHECK(w1.candidates[static_cast<std::size_t>(i)] == Eigen::Vector3d::Zero());
      const std::size_t x = i == kFilterCandidate ? kFilterFeatureOffset + 1 : 4 * i + 1;
      CHECK(w1.features[x] == 0.0f);
    }
    // Ages camera, LiDAR, radar at the window's end (0.2 s), / 5 s then
    // / 1 s; fresh; ray distances; |L - R|; ray direction.
    CheckFeatures(
        w1, kAgeOffset,
        {1.0, 0.1 / 5.0, 1.0, 1.0, 0.1, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0});

    // Window 2 [0.2, 0.4): a camera ray from the origin along +x (bearing not
    // unit) at 0.35 s and a radar point at 0.3 s, seen from the origin; the
    // LiDAR point is held from window 1. The radar point passes the gate: the
    // x axis at its range sqrt(29) is |(5, 2, 0) - (sqrt(29), 0, 0)| = 2.04 m
    // from it (<= 4); the LiDAR point came before any ray and did not.
    CameraObservation cam;
    cam.detected = true;
    cam.t_s = 0.35;
    cam.eye_left_w = Eigen::Vector3d::Zero();
    cam.bearing_left_w = {2.0, 0.0, 0.0};
    PointObservation radar;
    radar.channels = 5;
    radar.values = {5, 2, 0, 0, 0};
    radar.t_s = 0.3;
    arrived = {};
    arrived[kCamera] = AnchorOf(cam);
    arrived[kRadar] = AnchorOf(radar);
    const AnchorWindow w2 = tracker.Update(2, arrived);
    CheckCandidate(w2, 0, true, {1.0, 0.0, 0.0});
    CheckCandidate(w2, 1, true, {0.4, 0.0, -0.3});  // ((5, 2, 0) - c) / 10
    // No gated LiDAR fix: nothing of the LiDAR on the ray.
    CheckCandidate(w2, 2, false);
    CheckCandidate(w2, 4, false);
    // Radar (5, 2, 0) onto the x axis: (5, 0, 0), normalised (0.4, -0.2, -0.3).
    CheckCandidate(w2, 3, true, {0.4, -0.2, -0.3});
    // The x axis sqrt(29) m from the radar at the origin: t = sqrt(29).
    CheckCandidate(w2, 5, true, {(std::sqrt(29.0) - 1.0) / 10.0, -0.2, -0.3});
    // One fix each so far: nothing carried forward.
    CheckFeatures(w2, kMovingOffset, {0.0, 0.0});
    // At 0.4 s: camera 0.05 s old, LiDAR 0.3, radar 0.1.
    CheckFeatures(w2, kAgeOffset, {0.05 / 5.0, 0.3 / 5.0, 0.1 / 5.0, 0.05, 0.3, 0.1});
    CheckFeatures(w2, kFreshOffset, {1.0, 0.0, 1.0});
    // LiDAR is sqrt(2^2 + 3^2) from the x axis, radar 2: in units of 5 m.
    CheckFeatures(w2, kRayDistanceOffset, {std::sqrt(13.0) / 5.0, 2.0 / 5.0});
    // |(11, 2, 3) - (5, 2, 0)| = |(6, 0, 3)| = sqrt(45), over the 10 m scale.
    CheckFeatures(w2, kLidarRadarOffset, {std::sqrt(45.0) / 10.0});
    CheckFeatures(w2, kDirectionOffset, {1.0, 0.0, 0.0});
    // The held ray for the head's free position: valid, origin (0 - c) / 10,
    // direction.
    CheckRay(w2, {1.0f, -0.1f, -0.2f, -0.3f, 1.0f, 0.0f, 0.0f});
    CheckRay(w1, {});
    // Gated: no LiDAR fix (saturated ages), the radar's 0.1 s old.
    CheckFeatures(w2, kGatedAgeOffset, {1.0, 0.1 / 5.0, 1.0, 0.1, 0.0, 0.0});

    // Window 3: nothing arrives, everything is held and 0.2 s older.
    const AnchorWindow w3 = tracker.Update(3, WindowAnchors{});
    for (int i = 0; i < 6; ++i) {
      const auto u = static_cast<std::size_t>(i);
      CHECK(w3.valid[u] == w2.valid[u]);
      CheckVector(w3.candidates[u], w2.candidates[u]);
    }
    CheckFeatures(w3, kAgeOffset,
                  {0.25 / 5.0, 0.5 / 5.0, 0.3 / 5.0, 0.25, 0.5, 0.3, 0.0, 0.0, 0.0});
    CheckFeatures(w3, kRayDistanceOffset,
                  {std::sqrt(13.0) / 5.0, 0.4, std::sqrt(45.0) / 10.0, 1.0, 0.0, 0.0});
    CheckFeatures(w3, kGatedAgeOffset, {1.0, 0.3 / 5.0, 1.0, 0.3, 0.0, 0.0});

    // Window 20 (end 4.0 s): camera 3.65 s old, LiDAR 3.9, radar 3.7; the
    // fine ages saturate.
    const AnchorWindow w20 = tracker.Update(20, WindowAnchors{});
    CheckFeatures(w20, kAgeOffset, {3.65 / 5.0, 3.9 / 5.0, 3.7 / 5.0, 1.0, 1.0, 1.0});

    // Window 21 (end 4.2 s): a new camera ray at 4.1 s replaces the old one:
    // from (1, 2, 3) along (0, 0.6, 0.8). LiDAR (11, 2, 3): p - o = (10, 0,
    // 0), along 0, at the distance |(10, -0.6, -0.8)| = sqrt(101). The gated
    // radar (5, 2, 0): p - o = (4, 0, -3), along -2.4, so the candidate is
    // o + 1 d = (1, 2.6, 3.8), normalised (0, 0.06, 0.08); distance
    // |(4, -0.6, -3.8)| = sqrt(16 + 0.36 + 14.44).
    arrived = {};
    arrived[kCamera] = Ray(centre, {0.0, 3.0, 4.0}, 4.1);
    const AnchorWindow w21 = tracker.Update(21, arrived);
    CheckCandidate(w21, 2, false);
    CheckCandidate(w21, 3, true, {0.0, 0.06, 0.08});
    // Radar at sqrt(29) m from the origin along o + t d: t^2 + 7.2 t + 14 =
    // 29, t = -3.6 + sqrt(27.96) (the other crossing is behind the eye).
    const double t5 = -3.6 + std::sqrt(27.96);
    CheckCandidate(w21, 5, true, {0.0, 0.06 * t5, 0.08 * t5});
    CheckFeatures(w21, kAgeOffset, {0.1 / 5.0, 4.1 / 5.0, 3.9 / 5.0, 0.1, 1.0, 1.0, 1.0, 0.0, 0.0});
    CheckFeatures(
        w21, kRayDistanceOffset,
        {std::sqrt(101.0) / 5.0, std::sqrt(30.8) / 5.0, std::sqrt(45.0) / 10.0, 0.0, 0.6, 0.8});

    // Window 31 (end 6.2 s): the LiDAR and radar points are more than 5 s
    // old and give no candidates; the ray (2.1 s) alone gives none either.
    const AnchorWindow w31 = tracker.Update(31, WindowAnchors{});
    for (int i = 0; i < kAnchorCandidates; ++i) CheckCandidate(w31, i, false);
    CheckFeatures(w31, kAgeOffset, {2.1 / 5.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0});
    CheckFeatures(w31, kDirectionOffset, {0.0, 0.6, 0.8});
    CheckRay(w31, {1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.6f, 0.8f});

    // Reset: nothing held any more.
    tracker.Reset();
    CheckNothingHeld(tracker.Update(42, WindowAnchors{}));
  }
}

TEST_CASE("AnchorTracker: points carried forward at the velocity of their last two fixes",
          "[pipeline]") {
  AnchorTracker tracker(0.2, Eigen::Vector3d::Zero(), 10.0);
  // A LiDAR at the origin; its fixes carry their mean range.
  const auto lidar_fix = [](const Eigen::Vector3d& p, double t_s) {
    GeometricAnchor a = Point(p.x(), p.y(), p.z(), t_s);
    a.range_m = p.norm();
    return a;
  };
  std::array<GeometricAnchor, kModalityCount> arrived;
  arrived[kCamera] = Ray(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.15);
  arrived[kLidar] = lidar_fix({0.0, 0.0, 30.0}, 0.1);
  const AnchorWindow w1 = tracker.Update(1, arrived);
  CheckCandidate(w1, 0, true, {0.0, 0.0, 3.0});  // as seen: one fix
  CheckFeatures(w1, kMovingOffset, {0.0, 0.0});
  // Window 3 [0.4, 0.6): a second LiDAR fix 1 m east (within the 1.5 m
  // gate of the ray), 0.4 s later: 2.5 m/s.
  arrived = {};
  arrived[kLidar] = lidar_fix({1.0, 0.0, 30.0}, 0.5);
  const AnchorWindow w3 = tracker.Update(3, arrived);
  CheckFeatures(w3, kMovingOffset, {1.0, 0.0});
  CheckFeatures(w3, kGatedMovingOffset, {1.0, 0.0});
  // At the window's end (0.6 s): 1 + 2.5 * 0.1 = 1.25 m east.
  CheckCandidate(w3, 0, true, {0.125, 0.0, 3.0});
  CheckCandidate(w3, 2, true, {0.0, 0.0, 3.0});  // onto the z axis
  // The range 30 -> sqrt(901) in 0.4 s, carried 0.1 s on; the z axis at it.
  const double range = std::sqrt(901.0) + (std::sqrt(901.0) - 30.0) / 0.4 * 0.1;
  CheckCandidate(w3, 4, true, {0.0, 0.0, range / 10.0});
  for (int i : {1, 3, 5}) CheckCandidate(w3, i, false);  // no radar
  // Window 4, nothing new: 1 + 2.5 * 0.3 = 1.75 m east.
  CheckCandidate(tracker.Update(4, WindowAnchors{}), 0, true, {0.175, 0.0, 3.0});
  // Window 10 (end 2 s): the point carried for at most 1 s, 1 + 2.5 = 3.5 m
  // east; the ray's candidates for up to 3 s: the range 1.5 s on.
  const double range_rate = (std::sqrt(901.0) - 30.0) / 0.4;
  const AnchorWindow w10 = tracker.Update(10, WindowAnchors{});
  CheckCandidate(w10, 0, true, {0.35, 0.0, 3.0});
  CheckCandidate(w10, 4, true, {0.0, 0.0, (std::sqrt(901.0) + 1.5 * range_rate) / 10.0});
  // Window 20 (end 4 s): the range 3 s on at most.
  CheckCandidate(tracker.Update(20, WindowAnchors{}), 4, true,
                 {0.0, 0.0, (std::sqrt(901.0) + 3.0 * range_rate) / 10.0});
  // Window 27 (end 5.4 s): the point 4.9 s old, still held; the ray 5.25 s,
  // no more candidates on it. Window 28: the point 5.1 s old, gone.
  const AnchorWindow w27 = tracker.Update(27, WindowAnchors{});
  CheckCandidate(w27, 0, true, {0.35, 0.0, 3.0});
  CheckCandidate(w27, 4, false);
  CheckCandidate(tracker.Update(28, WindowAnchors{}), 0, false);

  // Implausible speeds and fixes too far apart in time carry nothing: the
  // point stays as last seen.
  AnchorTracker fast(0.2, Eigen::Vector3d::Zero(), 10.0);
  arrived = {};
  arrived[kRadar] = Point(0.0, 0.0, 30.0, 0.1);
  fast.Update(1, arrived);
  arrived[kRadar] = Point(10.0, 0.0, 30.0, 0.2);  // 100 m/s
  const AnchorWindow f = fast.Update(2, arrived);
  CheckCandidate(f, 1, true, {1.0, 0.0, 3.0});
  CheckFeatures(f, kMovingOffset, {0.0, 0.0});
  AnchorTracker slow(0.2, Eigen::Vector3d::Zero(), 10.0);
  arrived[kRadar] = Point(0.0, 0.0, 30.0, 0.1);
  slow.Update(1, arrived);
  arrived[kRadar] = Point(1.0, 0.0, 30.0, 2.5);  // 2.4 s later
  const AnchorWindow sl = slow.Update(13, arrived);
  CheckCandidate(sl, 1, true, {0.1, 0.0, 3.0});
  CheckFeatures(sl, kMovingOffset, {0.0, 0.0});
  // Just over and just under the 20 m/s bound, for the position and for
  // the mean range.
  for (const auto& [dx, dr, moving] : {std::tuple{4.2, 0.0, false}, std::tuple{3.8, 0.0, true},
                                       std::tuple{1.0, 4.2, false}, std::tuple{1.0, -3.8, true}}) {
    INFO("moved " << dx << " m, range " << dr << " m in 0.2 s");
    AnchorTracker t(0.2, Eigen::Vector3d::Zero(), 10.0);
    arrived = {};
    arrived[kRadar] = Point(0.0, 0.0, 30.0, 0.1);
    arrived[kRadar].range_m = 30.0;
    t.Update(1, arrived);
    arrived[kRadar] = Point(dx, 0.0, 30.0, 0.3);
    arrived[kRadar].range_m = 30.0 + dr;
    CheckFeatures(t.Update(2, arrived), kMovingOffset, {0.0, moving ? 1.0 : 0.0});
  }
}

TEST_CASE("AnchorTracker: the ray's candidates take only the fixes that agree with the ray",
          "[pipeline]") {
  AnchorTracker tracker(0.2, Eigen::Vector3d::Zero(), 10.0);
  std::array<GeometricAnchor, kModalityCount> arrived;
  // Window 1: a ray from the origin along z at 0.1 s; a LiDAR fix 1.4 m off
  // it (within the 1.5 m gate) at 0.15 s.
  arrived[kCamera] = Ray(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.1);
  arrived[kLidar] = Point(1.4, 0.0, 20.0, 0.15);
  CheckCandidate(tracker.Update(1, arrived), 2, true, {0.0, 0.0, 2.0});
  // Window 2: 1.6 m off the ray: held (candidate 0, carried at its 1 m/s
  // from the last fix: 1.6 + 0.05 at 0.4 s) but not on the ray's side,
  // which keeps the gated fix of window 1, 0.25 s old.
  arrived = {};
  arrived[kLidar] = Point(1.6, 0.0, 20.0, 0.35);
  const AnchorWindow w2 = tracker.Update(2, arrived);
  CheckCandidate(w2, 0, true, {0.165, 0.0, 2.0});
  CheckCandidate(w2, 2, true, {0.0, 0.0, 2.0});
  CheckFeatures(w2, kGatedAgeOffset, {0.25 / 5.0, 1.0, 0.25, 1.0, 0.0, 0.0});
  // Window 3: (0, 0, 21) at 0.55 s, 0.45 s after the ray: gated. The gated
  // fixes (1.4, 0, 20) at 0.15 s and (0, 0, 21) at 0.55 s give (-3.5, 0,
  // 2.5) m/s; at 0.6 s z = 21.125, onto the ray (0, 0, 21.125).
  arrived[kLidar] = Point(0.0, 0.0, 21.0, 0.55);
  const AnchorWindow w3 = tracker.Update(3, arrived);
  CheckCandidate(w3, 2, true, {0.0, 0.0, 2.1125});
  CheckFeatures(w3, kGatedMovingOffset, {1.0, 0.0});
  // Window 4: on the ray but 0.55 s after it: too far apart in time.
  arrived[kLidar] = Point(0.0, 0.0, 21.0, 0.65);
  const AnchorWindow w4 = tracker.Update(4, arrived);
  CheckFeatures(w4, kGatedAgeOffset, {0.25 / 5.0, 1.0, 0.25, 1.0});
  CheckFeatures(w4, kAgeOffset + 4, {0.15});  // the held (ungated) LiDAR fix

  // The radar: its centroid against the ray's point at the radar's range
  // (its angles are degrees off, its range is not). Radar at the origin, a
  // fix at (3, 0, 20), range sqrt(409): the ray's point (0, 0, sqrt(409)) is
  // sqrt(9 + (sqrt(409) - 20)^2) = 3.008 m away, within the 4 m gate; at
  // (5, 0, 20) it is 5.04 m away.
  for (const auto& [x, gated] : {std::pair{3.0, true}, std::pair{5.0, false}}) {
    INFO("radar fix at x = " << x);
    AnchorTracker r(0.2, Eigen::Vector3d::Zero(), 10.0);
    arrived = {};
    arrived[kCamera] = Ray(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.1);
    arrived[kRadar] = Point(x, 0.0, 20.0, 0.1);
    arrived[kRadar].range_m = std::hypot(x, 20.0);
    const AnchorWindow w = r.Update(1, arrived);
    CheckCandidate(w, 1, true, {x / 10.0, 0.0, 2.0});
    if (gated) {
      CheckCandidate(w, 3, true, {0.0, 0.0, 2.0});
      CheckCandidate(w, 5, true, {0.0, 0.0, std::hypot(x, 20.0) / 10.0});
    } else {
      CheckCandidate(w, 3, false);
      CheckCandidate(w, 5, false);
    }
  }
}

TEST_CASE("AnchorTracker: distance features are clipped at 4", "[pipeline]") {
  AnchorTracker tracker(0.1, Eigen::Vector3d::Zero(), 10.0);
  std::array<GeometricAnchor, kModalityCount> arrived;
  arrived[kCamera] = Ray(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  arrived[kLidar] = Point(30.0, 0.0, 50.0);   // 30 m from the ray: 6 -> 4
  arrived[kRadar] = Point(-19.0, 0.0, 50.0);  // 19 m: 3.8; |L - R| 49 m: 4.9 -> 4
  const AnchorWindow w = tracker.Update(7, arrived);
  CheckFeatures(w, kRayDistanceOffset, {4.0, 3.8, 4.0});
  // Both far off the ray: neither passes the gate.
  CheckCandidate(w, 2, false);
  CheckCandidate(w, 3, false);
  // A single held anchor gives no LiDAR-radar distance.
  AnchorTracker only_radar(0.1, Eigen::Vector3d::Zero(), 10.0);
  arrived = {};
  arrived[kRadar] = Point(-19.0, 0.0, 50.0);
  const AnchorWindow r = only_radar.Update(1, arrived);
  CheckFeatures(r, kRayDistanceOffset, {0.0, 0.0, 0.0, 0.0, 0.0, 0.0});
}

TEST_CASE("AnchorTracker: refuses a window length or scale that is not positive", "[pipeline]") {
  const Eigen::Vector3d c = Eigen::Vector3d::Zero();
  CHECK_THROWS_AS(AnchorTracker(0.0, c, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(AnchorTracker(-0.2, c, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(AnchorTracker(std::nan(""), c, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(AnchorTracker(0.2, c, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(AnchorTracker(0.2, c, std::numeric_limits<double>::infinity()),
                  std::invalid_argument);
  CHECK_NOTHROW(AnchorTracker(0.2, c, 1.0));
}

TEST_CASE("AnchorTracker: the filter's track is the seventh candidate", "[pipeline]") {
  const Eigen::Vector3d centre(1.0, 2.0, 3.0);
  AnchorTracker tracker(0.2, centre, 10.0);
  // Window 1 [0, 0.2): a ray along +x at 0.05 s, then a LiDAR centroid
  // (20, 0, 0) at 0.1 s on it: the track starts there, at rest, at 0.1 s; a
  // second ray at 0.15 s through (20, 0, 0) leaves it there.
  WindowAnchors arrived;
  arrived[kCamera] = {Ray({0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, 0.05),
                      Ray({0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, 0.15)};
  arrived[kLidar] = {Point(20.0, 0.0, 0.0, 0.1)};
  const AnchorWindow w1 = tracker.Update(1, arrived);
  CheckCandidate(w1, kFilterCandidate, true, (Eigen::Vector3d(20.0, 0.0, 0.0) - centre) / 10.0);
  // The tracker's filter is the IMM of a quiet coordinated turn and a
  // constant velocity. At rest (v = 0, so the turn's omega column is zero
  // and both modes move [p, v] per axis by F = [1 dt; 0 1], with
  // Q = q [dt^3/3 dt^2/2; dt^2/2 dt] of their own q), worked by hand: from
  // the start at 0.1 s (P0 = diag(sL^2, sV^2), mode probabilities 1/2 each)
  // to the ray at 0.15 s, its update of y and z (noise r2 = (20
  // sigma_theta)^2 + floor^2, no innovation: the modes' likelihoods go as
  // 1 / S, S = P_pp + r2 per axis, squared over the two axes and square
  // rooted), then to the deadline 0.2 s; each step first mixes the modes
  // (the same means: P_j <- sum_i pi_ij mu_i P_i / c_j, c_j = sum_i pi_ij
  // mu_i, leaving a mode with probability 1 - exp(-dt / kModeSwitch_s)).
  using Modes = std::array<std::array<Eigen::Matrix2d, 3>, 2>;  // [mode][axis]
  const std::array<double, 2> q_mode = {AnchorFilter::kTurnAccelPsd, AnchorFilter::kAccelPsd};
  std::array<double, 2> mu = {0.5, 0.5};
  Modes modes;
  for (auto& mode : modes)
    for (auto& axis : mode)
      axis = Eigen::Vector2d(std::pow(AnchorFilter::kLidarSigma_m, 2),
                             std::pow(AnchorFilter::kStartSpeedSigma_mps, 2))
                 .asDiagonal();
  const auto step = [&](double dt) {
    const double leave = 1.0 - std::exp(-dt / AnchorFilter::kModeSwitch_s);
    const auto pi = [&](int i, int k) { return i == k ? 1.0 - leave : leave; };
    Modes mixed;
    std::array<double, 2> c{};
    Eigen::Matrix2d f;
    f << 1.0, dt, 0.0, 1.0;
    for (int k = 0; k < 2; ++k) {
      c[k] = pi(0, k) * mu[0] + pi(1, k) * mu[1];
      Eigen::Matrix2d q;
      q << dt * dt * dt / 3.0, dt * dt / 2.0, dt * dt / 2.0, dt;
      for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Matrix2d p =
            (pi(0, k) * mu[0] * modes[0][axis] + pi(1, k) * mu[1] * modes[1][axis]) / c[k];
        mixed[k][axis] = f * p * f.transpose() + q_mode[k] * q;
      }
    }
    modes = mixed, mu = c;
  };
  step(0.05);
  const double r2 = std::pow(20.0 * AnchorFilter::kRaySigma_rad, 2) +
                    AnchorFilter::kRayFloor_m * AnchorFilter::kRayFloor_m;
  std::array<double, 2> weight{};
  for (int k = 0; k < 2; ++k) {
    const double s_yz = modes[k][1](0, 0) + r2;  // y and z alike
    weight[k] = mu[k] / s_yz;
    for (int axis = 1; axis < 3; ++axis) {
      Eigen::Matrix2d& p = modes[k][axis];
      const Eigen::Vector2d gain = p.col(0) / s_yz;
      p -= gain * p.row(0);  // (I - K H) P
    }
  }
  mu = {weight[0] / (weight[0] + weight[1]), weight[1] / (weight[0] + weight[1])};
  step(0.05);
  double trace = 0.0;
  for (int k = 0; k < 2; ++k)
    for (int axis = 0; axis < 3; ++axis) trace += mu[k] * modes[k][axis](0, 0);
  CheckFeatures(w1, kFilterFeatureOffset + 4,
                {std::sqrt(trace) / AnchorTracker::kSigmaUnit_m, 0.1 / 5.0, 0.1});
  // Nothing more arrives: the track coasts, then ends kMaxPredict_s after
  // its LiDAR fix.
  const auto coast_windows = static_cast<std::int64_t>(AnchorFilter::kMaxPredict_s / 0.2);
  CheckCandidate(tracker.Update(coast_windows, WindowAnchors{}), kFilterCandidate, true,
                 (Eigen::Vector3d(20.0, 0.0, 0.0) - centre) / 10.0);
  const AnchorWindow ended = tracker.Update(coast_windows + 1, WindowAnchors{});
  CheckCandidate(ended, kFilterCandidate, false);
  CheckFeatures(ended, kFilterFeatureOffset, {0.0, 0.0, 0.0, 0.0, 4.0, 1.0, 1.0});
  // Reset forgets the track.
  tracker.Reset();
  CheckCandidate(tracker.Update(1, WindowAnchors{}), kFilterCandidate, false);
}

TEST_CASE("TeAlign: AnchorsOf takes the window's anchored frames in capture order", "[pipeline]") {
  TeAlignConfig config;
  config.latent_dim = 4;
  const TeAlign align(config);
  WindowInputs in;
  in.window = 3;  // [0.4, 0.6)
  const Eigen::Vector3d o(1.0, 2.0, 3.0);
  auto& camera = in.frames[kCamera];
  camera.push_back(Frame(0.61, Ray(o, {1.0, 0.0, 0.0})));  // next window: ignored
  camera.push_back(Frame(0.55, Ray(o, {0.0, 1.0, 0.0})));  // the latest with a ray
  camera.push_back(Frame(0.41, Ray(o, {0.0, 0.0, 1.0})));
  camera.push_back(Frame(0.58, GeometricAnchor{}));         // later but nothing detected
  camera.push_back(Frame(0.39, Ray(o, {-1.0, 0.0, 0.0})));  // previous window: ignored
  auto& lidar = in.frames[kLidar];
  lidar.push_back(Frame(0.45, Point(1.0, 1.0, 1.0)));
  lidar.push_back(Frame(0.40, Point(2.0, 2.0, 2.0)));  // on the window's start
  lidar.push_back(Frame(0.60, Point(3.0, 3.0, 3.0)));  // on the next window's start
  auto& radar = in.frames[kRadar];
  radar.push_back(Frame(0.30, Point(4.0, 4.0, 4.0)));  // previous window
  radar.push_back(Frame(0.50, GeometricAnchor{}));
  radar.push_back(Frame(0.70, Point(5.0, 5.0, 5.0)));  // later window

  const WindowAnchors got = align.AnchorsOf(in);
  REQUIRE(got[kCamera].size() == 2);
  CheckVector(got[kCamera][0].direction_w, {0.0, 0.0, 1.0});  // 0.41
  CheckVector(got[kCamera][1].direction_w, {0.0, 1.0, 0.0});  // 0.55
  REQUIRE(got[kLidar].size() == 2);
  CheckVector(got[kLidar][0].origin_w, {2.0, 2.0, 2.0});  // 0.40
  CheckVector(got[kLidar][1].origin_w, {1.0, 1.0, 1.0});  // 0.45
  CHECK(got[kRadar].empty());

  // Capture order whatever the order of arrival.
  std::swap(lidar[0], lidar[1]);
  CheckVector(align.AnchorsOf(in)[kLidar][0].origin_w, {2.0, 2.0, 2.0});
  // An empty window has no anchors.
  WindowInputs empty;
  empty.window = 3;
  for (const auto& anchors : align.AnchorsOf(empty)) CHECK(anchors.empty());
}

TEST_CASE("MedianCandidateOffsets: the per-axis median within the radius, in metres",
          "[pipeline]") {
  // Scale 10: candidates and truths normalised, offsets in metres.
  const double scale = 10.0;
  std::vector<AnchorWindow> windows;
  std::vector<Eigen::Vector3d> truth;
  // The track (candidate 6) in 7 windows: offsets (metres) whose per-axis
  // medians are 0.04, -0.01, 0.05 (sorted x: -0.3 0.0 0.02 0.04 0.06 0.1
  // 0.5), and one 3 m off (outside the 1 m radius: left out, else the x
  // median would be 0.05). The LiDAR point (candidate 0) in 4 of them:
  // median of an even count, the mean of the middle two. The radar point
  // (candidate 1) in 2, below min_windows 3: zero.
  const std::vector<Eigen::Vector3d> track = {
      {0.04, -0.01, 0.05}, {0.1, 0.2, 0.05},   {-0.3, -0.4, 0.05}, {0.0, 0.0, 0.06},
      {0.5, -0.02, 0.0},   {0.02, -0.01, 0.3}, {0.06, 0.3, -0.2},  {3.0, 0.0, 0.0}};
  const std::vector<double> lidar_x = {0.1, -0.2, 0.3, 0.0};
  for (std::size_t i = 0; i < track.size(); ++i) {
    AnchorWindow w;
    for (Eigen::Vector3d& c : w.candidates) c.setZero();
    const Eigen::Vector3d y(1.0 + i, -2.0, 3.0 * i);  // normalised
    w.valid[kFilterCandidate] = 1.0f;
    w.candidates[kFilterCandidate] = y + track[i] / scale;
    if (i < lidar_x.size()) {
      w.valid[0] = 1.0f;
      w.candidates[0] = y + Eigen::Vector3d(lidar_x[i], 0.0, 0.01) / scale;
    }
    if (i < 2) {
      w.valid[1] = 1.0f;
      w.candidates[1] = y + Eigen::Vector3d(0.2, 0.2, 0.2) / scale;
    }
    // An invalid candidate's position does not count.
    w.candidates[2] = y + Eigen::Vector3d(0.5, 0.5, 0.5) / scale;
    windows.push_back(w);
    truth.push_back(y);
  }
  const auto offsets = MedianCandidateOffsets(windows, truth, scale, 1.0, 3);
  CheckVector(offsets[kFilterCandidate], {0.04, -0.01, 0.05}, 1e-12);
  CheckVector(offsets[0], {0.05, 0.0, 0.01}, 1e-12);  // x: (0.0 + 0.1) / 2
  for (int c = 1; c < kFilterCandidate; ++c) CheckVector(offsets[c], {0.0, 0.0, 0.0}, 0.0);
  // The radius counts in metres: at 0.45 m the track's two offsets of
  // 0.50 m are left out too; of the five left, (0.04, -0.01, 0.05), (0.1,
  // 0.2, 0.05), (0.0, 0.0, 0.06), (0.02, -0.01, 0.3), (0.06, 0.3, -0.2), the
  // medians are 0.04, 0.0, 0.05; five are fewer than min_windows 6.
  CheckVector(MedianCandidateOffsets(windows, truth, scale, 0.45, 3)[kFilterCandidate],
              {0.04, 0.0, 0.05}, 1e-12);
  CheckVector(MedianCandidateOffsets(windows, truth, scale, 0.45, 6)[kFilterCandidate],
              {0.0, 0.0, 0.0}, 0.0);
  truth.pop_back();
  CHECK_THROWS_AS(MedianCandidateOffsets(windows, truth, scale, 1.0, 3), std::invalid_argument);
  truth.emplace_back(0.0, 0.0, 0.0);
  CHECK_THROWS_AS(MedianCandidateOffsets(windows, truth, 0.0, 1.0, 3), std::invalid_argument);
  CHECK_THROWS_AS(MedianCandidateOffsets(windows, truth, scale, -1.0, 3), std::invalid_argument);
}

}  // namespace uavsim::pipeline
