// The edge's constant-velocity Kalman filter over the geometric anchors
// (pipeline/anchored/anchor_filter.h): when a track starts (a LiDAR fix that agrees
// with the camera's ray, there; two radar fixes that agree with the ray and
// with each other at the ray's crossings of their range spheres, at the
// second as the radar gives it), the
// prediction's covariance, the LiDAR, ray and radar updates against the
// Kalman closed forms worked out per axis by hand, a constant-velocity target
// followed to its analytic trajectory, the gate and the restart at a LiDAR
// fix on the ray that the track rejects, the radar's radial velocity (and a radar
// start's velocity along its line of sight), coasting and Reset; the
// coordinated turn against the circle and central differences, and the IMM
// of a turn and a constant velocity coasting an orbit and handing over
// through a manoeuvre. (The IMM's mixing against a hand-worked case:
// tests/pipeline/anchored/anchors_test.cpp.)
#include "pipeline/anchored/anchor_filter.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace uavsim::pipeline {
namespace {

using Kind = GeometricAnchor::Kind;
using Estimate = AnchorFilter::Estimate;

constexpr double kSigmaL = AnchorFilter::kLidarSigma_m;
constexpr double kSigmaV = AnchorFilter::kStartSpeedSigma_mps;
constexpr double kQ = AnchorFilter::kAccelPsd;

GeometricAnchor Ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& towards, double t_s) {
  GeometricAnchor a;
  a.kind = Kind::kRay;
  a.origin_w = origin;
  a.direction_w = (towards - origin).normalized();
  a.t_s = t_s;
  return a;
}

GeometricAnchor Lidar(const Eigen::Vector3d& p, double t_s) {
  GeometricAnchor a;
  a.kind = Kind::kPoint;
  a.origin_w = p;
  a.t_s = t_s;
  return a;
}

GeometricAnchor Radar(const Eigen::Vector3d& centroid, const Eigen::Vector3d& sensor,
                      double range_m, double t_s) {
  GeometricAnchor a;
  a.kind = Kind::kPoint;
  a.origin_w = centroid;
  a.sensor_w = sensor;
  a.range_m = range_m;
  a.t_s = t_s;
  return a;
}

// The distance of p from the (infinite) line of the ray.
double DistanceFromLine(const Eigen::Vector3d& p, const GeometricAnchor& ray) {
  const Eigen::Vector3d r = p - ray.origin_w;
  return (r - r.dot(ray.direction_w) * ray.direction_w).norm();
}

// The position variance per axis of a fresh start predicted dt ahead:
// sigma_L^2 + sigma_V^2 dt^2 + q dt^3 / 3.
double StartVarianceAfter(double dt) {
  return kSigmaL * kSigmaL + kSigmaV * kSigmaV * dt * dt + kQ * dt * dt * dt / 3.0;
}

void CheckVector(const Eigen::Vector3d& got, const Eigen::Vector3d& expected, double tol = 1e-9) {
  INFO("got (" << got.transpose() << "), expected (" << expected.transpose() << ")");
  CHECK((got - expected).norm() <= tol);
}

// The estimate at t_s exists and sits at `expected`.
Estimate CheckAt(const AnchorFilter& f, double t_s, const Eigen::Vector3d& expected,
                 double tol = 1e-9) {
  INFO("PredictAt(" << t_s << ")");
  const std::optional<Estimate> e = f.PredictAt(t_s);
  REQUIRE(e.has_value());
  CheckVector(e->position_m, expected, tol);
  return *e;
}

// The scene most cases share: a camera at kEye looking at kTarget.
const Eigen::Vector3d kEye(0.0, 0.0, 1.5);
const Eigen::Vector3d kTarget(40.0, -10.0, 20.0);

// A filter started at t_s by a ray from kEye through kTarget and a LiDAR fix
// exactly on it (so the start is kTarget itself).
AnchorFilter StartedAt(double t_s) {
  AnchorFilter f;
  f.Observe(Modality::kCamera, Ray(kEye, kTarget, t_s));
  f.Observe(Modality::kLidar, Lidar(kTarget, t_s));
  return f;
}

}  // namespace

TEST_CASE("AnchorFilter: nothing before a start and mismatched anchors throw", "[pipeline]") {
  const double t = 5.0;
  AnchorFilter f;
  CHECK_FALSE(f.PredictAt(t).has_value());

  // A LiDAR fix with no ray yet starts nothing.
  f.Observe(Modality::kLidar, Lidar(kTarget, t));
  CHECK_FALSE(f.PredictAt(t).has_value());

  // Rays alone do not fix the range.
  for (int i = 0; i < 5; ++i) f.Observe(Modality::kCamera, Ray(kEye, kTarget, t + 0.1 * i));
  CHECK_FALSE(f.PredictAt(t + 0.4).has_value());

  // A LiDAR fix 10 m off the latest ray (normal to it) starts nothing.
  const GeometricAnchor ray = Ray(kEye, kTarget, t + 0.5);
  f.Observe(Modality::kCamera, ray);
  const Eigen::Vector3d normal = ray.direction_w.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d off = kTarget + 10.0 * normal;
  REQUIRE(DistanceFromLine(off, ray) == Approx(10.0).epsilon(1e-12));
  f.Observe(Modality::kLidar, Lidar(off, t + 0.5));
  CHECK_FALSE(f.PredictAt(t + 0.5).has_value());

  // On the ray but more than RayGate::kGateMaxAge_s after it: nothing.
  f.Observe(Modality::kLidar, Lidar(kTarget, t + 0.5 + RayGate::kGateMaxAge_s + 0.1));
  CHECK_FALSE(f.PredictAt(t + 1.1).has_value());

  // A kNone anchor is ignored whatever the modality.
  CHECK_NOTHROW(f.Observe(Modality::kCamera, GeometricAnchor{}));
  CHECK_NOTHROW(f.Observe(Modality::kLidar, GeometricAnchor{}));

  // A point for the camera, a ray for the LiDAR or the radar.
  CHECK_THROWS_AS(f.Observe(Modality::kCamera, Lidar(kTarget, t)), std::invalid_argument);
  CHECK_THROWS_AS(f.Observe(Modality::kLidar, Ray(kEye, kTarget, t)), std::invalid_argument);
  CHECK_THROWS_AS(f.Observe(Modality::kRadar, Ray(kEye, kTarget, t)), std::invalid_argument);
  CHECK_FALSE(f.PredictAt(t + 1.1).has_value());
}

TEST_CASE("AnchorFilter: a LiDAR fix that agrees with the ray starts a static track there",
          "[pipeline]") {
  // Ray from (1, 2, 3) along (2, 1, 0.5) / |.|, the fix 0.6 m off it (inside
  // the 1.5 m gate), 30 m along, 0.2 s after the ray: the start is the fix
  // itself (the ray may be older than the drone's last move), at 1.2 s.
  const Eigen::Vector3d o(1.0, 2.0, 3.0);
  const Eigen::Vector3d d = Eigen::Vector3d(2.0, 1.0, 0.5).normalized();
  const Eigen::Vector3d n = d.cross(Eigen::Vector3d::UnitZ()).normalized();  // normal to d
  const Eigen::Vector3d c = o + 30.0 * d + 0.6 * n;
  const Eigen::Vector3d start = c;

  AnchorFilter f;
  f.Observe(Modality::kCamera, Ray(o, o + d, 1.0));
  f.Observe(Modality::kLidar, Lidar(c, 1.2));

  // At the start time: sigma_m = sqrt(3 sigma_L^2), nothing since the fix.
  const Estimate e0 = CheckAt(f, 1.2, start);
  CHECK(e0.sigma_m == Approx(std::sqrt(3.0) * kSigmaL).epsilon(1e-12));
  CHECK(e0.ranging_age_s == Approx(0.0).margin(1e-12));

  // Zero velocity: the same position at any later time; the covariance
  // F P F^T + Q with P = diag(sigma_L^2 I, sigma_V^2 I).
  for (const double dt : {0.1, 0.5, 1.5}) {
    INFO("dt " << dt);
    const Estimate e = CheckAt(f, 1.2 + dt, start);
    CHECK(e.sigma_m == Approx(std::sqrt(3.0 * StartVarianceAfter(dt))).epsilon(1e-12));
    CHECK(e.ranging_age_s == Approx(dt).epsilon(1e-12));
  }
  // dt = 0.5 by hand: 0.0225 + 36 * 0.25 + 2 * 0.125 / 3 = 9.105833...
  CHECK(f.PredictAt(1.7)->sigma_m == Approx(std::sqrt(3.0 * (0.0225 + 9.0 + 0.25 / 3.0))));

  // PredictAt does not move the track: the start time's estimate again.
  CHECK(f.PredictAt(1.2)->sigma_m == Approx(std::sqrt(3.0) * kSigmaL).epsilon(1e-12));

  // A fix 1.6 m off the ray starts nothing.
  AnchorFilter g;
  g.Observe(Modality::kCamera, Ray(o, o + d, 1.0));
  g.Observe(Modality::kLidar, Lidar(o + 30.0 * d + 1.6 * n, 1.0));
  CHECK_FALSE(g.PredictAt(1.0).has_value());
}

TEST_CASE("AnchorFilter: a second LiDAR fix is the per-axis Kalman update", "[pipeline]") {
  const double t0 = 2.0;
  const double s2 = kSigmaL * kSigmaL;

  SECTION("at the start's time: the mean of the two fixes") {
    AnchorFilter f = StartedAt(t0);
    const Eigen::Vector3d delta(0.1, -0.05, 0.08);
    f.Observe(Modality::kLidar, Lidar(kTarget + delta, t0));
    // Gain sigma_L^2 / (sigma_L^2 + sigma_L^2) = 1/2 per axis.
    const Estimate e = CheckAt(f, t0, kTarget + 0.5 * delta, 1e-12);
    // Posterior variance sigma_L^2 / 2 per axis.
    CHECK(e.sigma_m == Approx(std::sqrt(3.0 * s2 / 2.0)).epsilon(1e-12));
    CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));
    // The velocity's gain is zero (no cross covariance): still static.
    const Estimate later = CheckAt(f, t0 + 1.0, kTarget + 0.5 * delta, 1e-12);
    CHECK(later.sigma_m == Approx(std::sqrt(3.0 * (s2 / 2.0 + kSigmaV * kSigmaV + kQ / 3.0))));
  }

  SECTION("dt after the start: predict then update with the 2x2 [p v] covariance") {
    AnchorFilter f = StartedAt(t0);
    const double dt = 0.1;
    const Eigen::Vector3d delta(0.3, -0.2, 0.1);
    f.Observe(Modality::kLidar, Lidar(kTarget + delta, t0 + dt));

    // Per axis: P' = [a b; b c] after the prediction.
    const double a = s2 + kSigmaV * kSigmaV * dt * dt + kQ * dt * dt * dt / 3.0;
    const double b = kSigmaV * kSigmaV * dt + kQ * dt * dt / 2.0;
    const double c = kSigmaV * kSigmaV + kQ * dt;
    const double s = a + s2;  // innovation variance
    const double kp = a / s, kv = b / s;
    // Posterior: p = p0 + kp delta, v = kv delta, P+ = P' - K S K^T.
    const Eigen::Vector3d p = kTarget + kp * delta;
    const Eigen::Vector3d v = kv * delta;
    const double pp = a - a * a / s, pv = b - a * b / s, vv = c - b * b / s;

    const Estimate e = CheckAt(f, t0 + dt, p);
    CHECK(e.sigma_m == Approx(std::sqrt(3.0 * pp)).epsilon(1e-9));
    CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));

    const double tau = 0.4;
    const Estimate ahead = CheckAt(f, t0 + dt + tau, p + tau * v);
    const double var = pp + 2.0 * tau * pv + tau * tau * vv + kQ * tau * tau * tau / 3.0;
    CHECK(ahead.sigma_m == Approx(std::sqrt(3.0 * var)).epsilon(1e-9));
    CHECK(ahead.ranging_age_s == Approx(tau).epsilon(1e-12));

    // The gains by hand: a = 0.0225 + 0.36 + 0.002 / 3, s = a + 0.0225.
    const double a_hand = 0.0225 + 0.36 + 0.002 / 3.0;
    CHECK(kp == Approx(a_hand / (a_hand + 0.0225)));
    CHECK(kv == Approx((3.6 + 0.01) / (a_hand + 0.0225)));
  }
}

TEST_CASE("AnchorFilter: a constant-velocity target is followed to its trajectory", "[pipeline]") {
  // p(t) = p0 + v (t - t0), a LiDAR fix and a ray from a fixed eye through
  // it every 0.1 s for 4 s; noiseless, so the filter's prediction 0.3 s past
  // the last fix converges on the trajectory.
  const double t0 = 10.0;
  const Eigen::Vector3d p0(40.0, -10.0, 20.0);
  const Eigen::Vector3d v(-2.0, 1.5, 0.3);
  const auto truth = [&](double t) -> Eigen::Vector3d { return p0 + v * (t - t0); };

  AnchorFilter f;
  double t = t0;
  for (int k = 0; k <= 40; ++k) {
    t = t0 + 0.1 * k;
    f.Observe(Modality::kCamera, Ray(kEye, truth(t), t));
    f.Observe(Modality::kLidar, Lidar(truth(t), t));
    // Every fix accepted: the age since the last ranging fix stays zero.
    const std::optional<Estimate> now = f.PredictAt(t);
    REQUIRE(now.has_value());
    CHECK(now->ranging_age_s == Approx(0.0).margin(1e-9));
  }
  const double ahead = t + 0.3;
  const std::optional<Estimate> e = f.PredictAt(ahead);
  REQUIRE(e.has_value());
  INFO("estimate (" << e->position_m.transpose() << "), truth (" << truth(ahead).transpose()
                    << ")");
  CHECK((e->position_m - truth(ahead)).norm() < 0.05);
  // The velocity: the prediction's displacement over 1 s is v.
  const std::optional<Estimate> e2 = f.PredictAt(ahead + 1.0);
  REQUIRE(e2.has_value());
  CHECK((e2->position_m - e->position_m - v).norm() < 0.05);
  // Static would be 0.3 |v| = 0.76 m off: the check above is not vacuous.
  CHECK((truth(ahead) - truth(t)).norm() > 0.7);
}

TEST_CASE("AnchorFilter: the constant-acceleration model's prediction and a turning target",
          "[pipeline]") {
  // Started at rest: per axis P0 = diag(sL^2, sV^2, sA^2); after dt the
  // position variance of F P0 F^T + Q, F = [1 dt dt^2/2; 0 1 dt; 0 0 1], Q =
  // j [dt^5/20 ...]: sL^2 + sV^2 dt^2 + sA^2 dt^4 / 4 + j dt^5 / 20.
  AnchorFilter f(AnchorFilter::Motion::kCa);
  CHECK(f.motion() == AnchorFilter::Motion::kCa);
  const double t0 = 4.0;
  f.Observe(Modality::kCamera, Ray(kEye, kTarget, t0));
  f.Observe(Modality::kLidar, Lidar(kTarget, t0));
  const double sa2 = std::pow(AnchorFilter::kStartAccelSigma_mps2, 2);
  const double j = AnchorFilter::kJerkPsd;
  for (double dt : {0.1, 0.5, 1.5}) {
    const double var = kSigmaL * kSigmaL + kSigmaV * kSigmaV * dt * dt + sa2 * std::pow(dt, 4) / 4 +
                       j * std::pow(dt, 5) / 20.0;
    const Estimate e = CheckAt(f, t0 + dt, kTarget);
    CHECK(e.sigma_m == Approx(std::sqrt(3.0 * var)).epsilon(1e-9));
  }
  // Reset keeps the motion model.
  f.Reset();
  CHECK(f.motion() == AnchorFilter::Motion::kCa);
  CHECK_FALSE(f.PredictAt(t0).has_value());

  // A target on a circle (6 m/s on 25 m, 1.44 m/s^2 towards the centre),
  // fixes and rays every 0.1 s for 4 s, noiseless: the constant-acceleration
  // model predicts 0.3 s past the last fix within centimetres (the turning
  // acceleration's own change, the jerk omega |a| = 0.35 m/s^3, is what it
  // does not model) and far closer than the constant-velocity one, which
  // cannot follow the turn.
  const Eigen::Vector3d centre(20.0, 0.0, 25.0);
  const double radius = 25.0, omega = 6.0 / 25.0;
  const auto truth = [&](double t) -> Eigen::Vector3d {
    return centre + radius * Eigen::Vector3d(std::cos(omega * t), std::sin(omega * t), 0.0);
  };
  AnchorFilter ca(AnchorFilter::Motion::kCa), cv(AnchorFilter::Motion::kCv);
  double t = 0.0;
  for (int k = 0; k <= 40; ++k) {
    t = 0.1 * k;
    for (AnchorFilter* g : {&ca, &cv}) {
      g->Observe(Modality::kCamera, Ray(kEye, truth(t), t));
      g->Observe(Modality::kLidar, Lidar(truth(t), t));
    }
  }
  const double ahead = t + 0.3;
  const double ca_error = (CheckAt(ca, ahead, truth(ahead), 1.0).position_m - truth(ahead)).norm();
  const double cv_error = (CheckAt(cv, ahead, truth(ahead), 1.0).position_m - truth(ahead)).norm();
  INFO("CA " << ca_error << " m, CV " << cv_error << " m");
  CHECK(ca_error < 0.06);
  CHECK(ca_error < 0.5 * cv_error);
}

TEST_CASE("AnchorFilter: a ray moves the estimate only normal to the ray", "[pipeline]") {
  // Just after a start (isotropic position covariance sigma_L^2 I, no cross
  // terms) a ray at the same time is a scalar update on each axis normal to
  // it: the distance from the ray shrinks by var / (sigma_L^2 + var), var =
  // (rho sigma_theta)^2 + sigma_ray^2, and nothing moves along it.
  const double t0 = 2.0;
  AnchorFilter f = StartedAt(t0);
  const Eigen::Vector3d o2(5.0, -3.0, 2.0);  // a second camera
  const GeometricAnchor ray = Ray(o2, kTarget + Eigen::Vector3d(0.1, 0.25, -0.15), t0);
  const double dist = DistanceFromLine(kTarget, ray);
  REQUIRE(dist > 0.1);

  f.Observe(Modality::kCamera, ray);
  const Eigen::Vector3d r = kTarget - o2;
  const double rho = std::max(1.0, r.dot(ray.direction_w));
  const double var = std::pow(rho * AnchorFilter::kRaySigma_rad, 2) +
                     AnchorFilter::kRayFloor_m * AnchorFilter::kRayFloor_m;
  const double s2 = kSigmaL * kSigmaL;
  const double gain = s2 / (s2 + var);

  const std::optional<Estimate> e = f.PredictAt(t0);
  REQUIRE(e.has_value());
  const Eigen::Vector3d moved = e->position_m - kTarget;
  CHECK(std::abs(moved.dot(ray.direction_w)) < 1e-9);
  CHECK(DistanceFromLine(e->position_m, ray) == Approx(dist * var / (s2 + var)).epsilon(1e-9));
  // The whole correction: - gain times the normal part of p - o.
  const Eigen::Vector3d normal_part = r - r.dot(ray.direction_w) * ray.direction_w;
  CheckVector(e->position_m, kTarget - gain * normal_part);
  // Two normal axes at sigma_L^2 var / (sigma_L^2 + var), one at sigma_L^2.
  CHECK(e->sigma_m == Approx(std::sqrt(s2 + 2.0 * s2 * var / (s2 + var))).epsilon(1e-9));
  // A ray is no ranging fix; the velocity is untouched (still static).
  CHECK(e->ranging_age_s == Approx(0.0).margin(1e-12));
  CheckAt(f, t0 + 0.5, e->position_m);
}

TEST_CASE("AnchorFilter: a radar fix updates along and across its line of sight", "[pipeline]") {
  // Isotropic prior sigma_L^2 I at the start's time; the radar's noise is
  // sigma_R^2 along u and (R sigma_angle)^2 across: a scalar update on each.
  const double t0 = 3.0;
  AnchorFilter f = StartedAt(t0);
  const Eigen::Vector3d sensor = kTarget + Eigen::Vector3d(-15.0, 8.0, -3.0);
  const Eigen::Vector3d nu(0.15, -0.3, 0.2);  // z - prediction
  const Eigen::Vector3d z = kTarget + nu;
  const double range = (z - sensor).norm();
  const Eigen::Vector3d u = (z - sensor) / range;
  // The centroid only gives the direction: put it short of the mean range.
  f.Observe(Modality::kRadar, Radar(sensor + 0.97 * range * u, sensor, range, t0));

  const double s2 = kSigmaL * kSigmaL;
  const double along_var = AnchorFilter::kRangeSigma_m * AnchorFilter::kRangeSigma_m;
  const double across_var = std::pow(range * AnchorFilter::kRadarAngleSigma_rad, 2);
  const Eigen::Vector3d along = nu.dot(u) * u;
  const Eigen::Vector3d across = nu - along;
  const Eigen::Vector3d expected =
      kTarget + s2 / (s2 + along_var) * along + s2 / (s2 + across_var) * across;
  const Estimate e = CheckAt(f, t0, expected);
  const double trace =
      s2 * along_var / (s2 + along_var) + 2.0 * s2 * across_var / (s2 + across_var);
  CHECK(e.sigma_m == Approx(std::sqrt(trace)).epsilon(1e-9));
  CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));
}

TEST_CASE("AnchorFilter: a radar's radial velocity updates the velocity along its line of sight",
          "[pipeline]") {
  // At rest at kTarget with P = diag(sigma_L^2 I, sigma_V^2 I): a radar fix
  // exactly there (no position innovation) with a radial velocity. At v = 0
  // the Jacobian of u . v has no position part, so the update is the scalar
  // gain sigma_V^2 / (sigma_V^2 + sigma_rdot^2) along u and nothing else.
  const double t0 = 2.0;
  AnchorFilter f = StartedAt(t0);
  const Eigen::Vector3d sensor = kTarget + Eigen::Vector3d(12.0, -20.0, -15.0);
  const double range = (kTarget - sensor).norm();
  const Eigen::Vector3d u = (kTarget - sensor) / range;
  GeometricAnchor radar = Radar(kTarget, sensor, range, t0);
  radar.has_range_rate = true;
  radar.range_rate_mps = 1.2;  // receding
  f.Observe(Modality::kRadar, radar);
  const double sv2 = kSigmaV * kSigmaV;
  const double rr2 = AnchorFilter::kRangeRateSigma_mps * AnchorFilter::kRangeRateSigma_mps;
  const Eigen::Vector3d v = sv2 / (sv2 + rr2) * 1.2 * u;
  // The position update is the radar's position-only one (innovation 0).
  CheckAt(f, t0, kTarget, 1e-12);
  // One second later the track has moved by v.
  CheckAt(f, t0 + 1.0, kTarget + v, 1e-9);
  CHECK(v.dot(u) > 1.1);  // receding: away from the radar
}

TEST_CASE("AnchorFilter: the gate rejects far fixes and a LiDAR fix on the ray restarts",
          "[pipeline]") {
  const double t0 = 1.0;
  // The target jumps 20 m: a new ray from the eye through q.
  const Eigen::Vector3d q = kTarget + Eigen::Vector3d(0.0, 20.0, 0.0);
  const GeometricAnchor ray2 = Ray(kEye, q, t0 + 0.1);
  const Eigen::Vector3d q_fix = q + 0.3 * ray2.direction_w.cross(Eigen::Vector3d::UnitZ());
  REQUIRE(DistanceFromLine(kTarget, ray2) > 5.0);
  const Eigen::Vector3d clutter = kTarget + Eigen::Vector3d(0.0, 0.0, -20.0);
  REQUIRE(DistanceFromLine(clutter, ray2) > RayGate::kLidarGate_m);

  SECTION("a fix 20 m away is rejected") {
    AnchorFilter f = StartedAt(t0);
    f.Observe(Modality::kLidar, Lidar(clutter, t0 + 0.1));
    const Estimate e = CheckAt(f, t0 + 0.1, kTarget, 1e-12);
    CHECK(e.ranging_age_s == Approx(0.1).epsilon(1e-9));
    CHECK(e.sigma_m == Approx(std::sqrt(3.0 * StartVarianceAfter(0.1))).epsilon(1e-9));
  }

  SECTION("a LiDAR fix that agrees with the ray but not with the track restarts at once") {
    AnchorFilter f = StartedAt(t0);
    f.Observe(Modality::kCamera, ray2);  // far from the track: rejected
    CheckAt(f, t0 + 0.1, kTarget, 1e-12);
    const double t = t0 + 0.2;
    f.Observe(Modality::kLidar, Lidar(q_fix, t));
    const Estimate e = CheckAt(f, t, q_fix);
    CHECK(e.sigma_m == Approx(std::sqrt(3.0) * kSigmaL).epsilon(1e-12));
    CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));
    CheckAt(f, t + 1.0, q_fix);  // a static start
  }

  SECTION("rejected clutter off the ray leaves the track; then a fix on the ray restarts") {
    AnchorFilter f = StartedAt(t0);
    f.Observe(Modality::kCamera, ray2);
    for (int i = 1; i <= AnchorFilter::kMaxRejections + 1; ++i) {
      f.Observe(Modality::kLidar, Lidar(clutter, t0 + 0.1 * i));
      CheckAt(f, t0 + 0.1 * i, kTarget, 1e-12);
    }
    const double t = t0 + 0.1 * (AnchorFilter::kMaxRejections + 2);
    f.Observe(Modality::kLidar, Lidar(q_fix, t));
    const Estimate e = CheckAt(f, t, q_fix);
    CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));
  }
}

TEST_CASE("AnchorFilter: two radar fixes on the ray that agree start a track", "[pipeline]") {
  // In a frame of our own: ray from the origin along x, radar at (30, 6, 0).
  // Range R crosses the x axis at (x - 30)^2 + 36 = R^2: R = 10 at x = 22 or
  // 38, R^2 = 108.25 at x = 30 +- 8.5. Everything rotated and moved to world.
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(100.0, -50.0, 10.0);
  const auto world = [&](double x, double y, double z) -> Eigen::Vector3d {
    return rot * Eigen::Vector3d(x, y, z) + shift;
  };
  const Eigen::Vector3d o = world(0.0, 0.0, 0.0);
  const Eigen::Vector3d radar = world(30.0, 6.0, 0.0);
  const double t0 = 4.0;
  const GeometricAnchor ray = Ray(o, world(1.0, 0.0, 0.0), t0);
  // Centroids near the far crossings (the near ones, x = 22 and 21.5, are
  // 16 m away).
  const GeometricAnchor first = Radar(world(38.0, 0.2, 0.0), radar, 10.0, t0);
  const GeometricAnchor second = Radar(world(38.5, 0.2, 0.1), radar, std::sqrt(108.25), t0 + 0.1);

  SECTION("without a ray nothing starts") {
    AnchorFilter f;
    f.Observe(Modality::kRadar, first);
    f.Observe(Modality::kRadar, second);
    CHECK_FALSE(f.PredictAt(t0 + 0.1).has_value());
  }

  // A radar start is the second fix as the radar gives it: its mean range
  // along its centroid's direction, with sigma_R^2 along and (R
  // sigma_angle)^2 across that direction (the ray may be old).
  const double r2 = std::sqrt(108.25);
  const Eigen::Vector3d radar_fix = radar + r2 * (world(38.5, 0.2, 0.1) - radar).normalized();
  const double radar_var = std::pow(AnchorFilter::kRangeSigma_m, 2) +
                           2.0 * std::pow(r2 * AnchorFilter::kRadarAngleSigma_rad, 2);

  SECTION("one fix waits, the second confirms it: start at the second fix") {
    AnchorFilter f;
    f.Observe(Modality::kCamera, ray);
    f.Observe(Modality::kRadar, first);
    CHECK_FALSE(f.PredictAt(t0).has_value());
    CHECK_FALSE(f.PredictAt(t0 + 0.1).has_value());
    f.Observe(Modality::kRadar, second);
    const Estimate e = CheckAt(f, t0 + 0.1, radar_fix);
    CHECK(e.sigma_m == Approx(std::sqrt(radar_var)).epsilon(1e-12));
    CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));
    CheckAt(f, t0 + 0.6, radar_fix);  // static
  }

  SECTION("with its radial velocity the start knows the velocity along the radar's sight") {
    // Confirmed at the crossing q = world(38.5, 0, 0), u = (q - radar) /
    // |q - radar| = rot (8.5, -6, 0) / sqrt(108.25): v = rdot u with
    // variance sigma_rdot^2 along u and sigma_V^2 across. Constant velocity,
    // dt on: position radar_fix + v dt; trace radar_var + dt^2 (2 sigma_V^2
    // + sigma_rdot^2) + q_a dt^3.
    AnchorFilter f;
    GeometricAnchor moving = second;
    moving.has_range_rate = true;
    moving.range_rate_mps = -3.0;  // approaching
    f.Observe(Modality::kCamera, ray);
    f.Observe(Modality::kRadar, first);
    f.Observe(Modality::kRadar, moving);
    const Eigen::Vector3d q = world(38.5, 0.0, 0.0);
    const Eigen::Vector3d u = rot * Eigen::Vector3d(8.5, -6.0, 0.0) / std::sqrt(108.25);
    REQUIRE((u - (q - radar).normalized()).norm() < 1e-12);
    const double dt = 0.5, rr2 = std::pow(AnchorFilter::kRangeRateSigma_mps, 2);
    const Estimate e = CheckAt(f, t0 + 0.1 + dt, radar_fix - 3.0 * dt * u);
    CHECK(e.sigma_m == Approx(std::sqrt(radar_var + dt * dt * (2.0 * kSigmaV * kSigmaV + rr2) +
                                        kQ * dt * dt * dt))
                           .epsilon(1e-9));
  }

  SECTION("a second fix too far from the first waits for a third") {
    // x = 44: R^2 = 14^2 + 36 = 232, 6 m on from 38 > kConfirm_m + 20 * 0.1.
    // x = 44.5: R^2 = 14.5^2 + 36 = 246.25, 0.5 m on from 44.
    AnchorFilter f;
    f.Observe(Modality::kCamera, ray);
    f.Observe(Modality::kRadar, first);
    f.Observe(Modality::kRadar, Radar(world(44.0, 0.2, 0.0), radar, std::sqrt(232.0), t0 + 0.1));
    CHECK_FALSE(f.PredictAt(t0 + 0.1).has_value());
    f.Observe(Modality::kRadar, Radar(world(44.5, -0.2, 0.0), radar, std::sqrt(246.25), t0 + 0.2));
    CheckAt(f, t0 + 0.2, radar + std::sqrt(246.25) * (world(44.5, -0.2, 0.0) - radar).normalized());
  }

  SECTION("radar fixes never take a running track over") {
    AnchorFilter f;
    f.Observe(Modality::kCamera, ray);
    f.Observe(Modality::kLidar, Lidar(world(22.0, 0.0, 0.0), t0));  // start at x = 22
    CheckAt(f, t0, world(22.0, 0.0, 0.0));
    // Radar fixes agreeing with the ray and each other at x = 38 and 38.5,
    // 16 m from the track: rejected however many come.
    for (int i = 1; i <= 2 * AnchorFilter::kMaxRejections; ++i) {
      const double t = t0 + 0.05 * i;
      f.Observe(Modality::kRadar, Radar(world(38.0, 0.2, 0.0), radar, 10.0, t));
      const Estimate e = CheckAt(f, t, world(22.0, 0.0, 0.0));
      CHECK(e.ranging_age_s == Approx(t - t0).epsilon(1e-9));
    }
  }
}

TEST_CASE("AnchorFilter: a track coasts after kMaxCoast_s and ends at kMaxPredict_s",
          "[pipeline]") {
  const double t0 = 1.0;  // t0 + kMaxCoast_s = 3.0, t0 + kMaxPredict_s = 6.0 exactly
  REQUIRE(AnchorFilter::kMaxCoast_s == 2.0);
  REQUIRE(AnchorFilter::kMaxPredict_s == 5.0);
  AnchorFilter f = StartedAt(t0);
  // The eye sees the target, a radar 20 m off it sees a clutter point on the
  // same ray 80 m farther: it agrees with the ray, not with the track (even
  // after 2.2 s of coasting, the along-ray variance sigma_L^2 + sigma_V^2 t^2
  // + q t^3 / 3 is 181 m^2: 80 m is 5.9 sigma, outside the 3.4 sigma gate).
  const Eigen::Vector3d d = (kTarget - kEye).normalized();
  const Eigen::Vector3d clutter = kTarget + 80.0 * d;
  const Eigen::Vector3d sensor = kTarget + Eigen::Vector3d(0.0, 20.0, -15.0);
  const auto radar = [&](double t) { return Radar(clutter, sensor, (clutter - sensor).norm(), t); };

  SECTION("rays alone do not keep it: it predicts until kMaxPredict_s") {
    for (int k = 1; k <= 25; ++k) f.Observe(Modality::kCamera, Ray(kEye, kTarget, t0 + 0.1 * k));
    const Estimate e = CheckAt(f, t0 + 2.5, kTarget, 1e-9);
    CHECK(e.ranging_age_s == Approx(2.5).epsilon(1e-9));
    CHECK(f.PredictAt(6.0).has_value());
    CHECK_FALSE(f.PredictAt(6.0 + 1e-6).has_value());
    // A LiDAR fix on the ray (here the target itself: accepted) keeps it.
    f.Observe(Modality::kLidar, Lidar(kTarget, t0 + 2.5));
    CHECK(CheckAt(f, t0 + 2.5, kTarget, 1e-9).ranging_age_s == Approx(0.0).margin(1e-12));
  }

  SECTION("while live, radar clutter on the ray never takes it over") {
    for (int k = 1; k <= 15; ++k) {
      const double t = t0 + 0.1 * k;
      f.Observe(Modality::kCamera, Ray(kEye, kTarget, t));
      f.Observe(Modality::kRadar, radar(t));
    }
    CheckAt(f, t0 + 1.5, kTarget, 1e-9);
  }

  SECTION("coasting, two confirming radar fixes on the ray take it over") {
    for (int k = 1; k <= 21; ++k) f.Observe(Modality::kCamera, Ray(kEye, kTarget, t0 + 0.1 * k));
    f.Observe(Modality::kRadar, radar(t0 + 2.1));  // rejected; waits for a confirmation
    CheckAt(f, t0 + 2.1, kTarget, 1e-9);
    f.Observe(Modality::kRadar, radar(t0 + 2.2));
    // The clutter's range on the ray: the crossing of the sphere nearer it.
    const Estimate e = CheckAt(f, t0 + 2.2, clutter, 1e-6);
    CHECK(e.ranging_age_s == Approx(0.0).margin(1e-12));
  }

  SECTION("an accepted fix restarts the clock") {
    f.Observe(Modality::kLidar, Lidar(kTarget, 2.5));
    CHECK(CheckAt(f, 7.5, kTarget, 1e-9).ranging_age_s == Approx(5.0).epsilon(1e-12));
    CHECK_FALSE(f.PredictAt(7.5 + 1e-6).has_value());
  }
}

TEST_CASE("AnchorFilter: Reset forgets the track and the ray", "[pipeline]") {
  const double t0 = 1.0;
  AnchorFilter f = StartedAt(t0);
  REQUIRE(f.PredictAt(t0).has_value());
  f.Reset();
  CHECK_FALSE(f.PredictAt(t0).has_value());
  CHECK_FALSE(f.PredictAt(t0 + 0.1).has_value());
  // The old ray is gone: a fix on it starts nothing.
  f.Observe(Modality::kLidar, Lidar(kTarget, t0 + 0.1));
  CHECK_FALSE(f.PredictAt(t0 + 0.1).has_value());
  // A fresh ray and fix start again.
  f.Observe(Modality::kCamera, Ray(kEye, kTarget, t0 + 0.2));
  f.Observe(Modality::kLidar, Lidar(kTarget, t0 + 0.2));
  CheckAt(f, t0 + 0.2, kTarget, 1e-9);
}

}  // namespace uavsim::pipeline

namespace uavsim::pipeline {
namespace {

using Vector10d = Eigen::Matrix<double, 10, 1>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;

// The state [p, v, a, omega] of a target on a horizontal circle (centre c,
// radius r, angular rate w, at angle phi), climbing at vz.
Vector10d OnCircle(const Eigen::Vector3d& c, double r, double w, double phi, double vz) {
  Vector10d x = Vector10d::Zero();
  x.head<3>() = c + Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), 0.0);
  x.segment<3>(3) = Eigen::Vector3d(-r * w * std::sin(phi), r * w * std::cos(phi), vz);
  x(9) = w;
  return x;
}

}  // namespace

TEST_CASE("AnchorFilter: the coordinated turn is the circle and its Jacobian the difference",
          "[pipeline]") {
  const Eigen::Vector3d c(5.0, -3.0, 30.0);
  Vector10d next;
  Matrix10d jacobian;
  // On the circle: after dt the angle has moved by w dt, the height by vz dt,
  // and the acceleration is dropped; clockwise too.
  for (double w : {0.24, -0.5, 1.3}) {
    for (double dt : {0.033, 0.2, 2.0}) {
      const double r = 25.0, phi = 0.7, vz = 0.4;
      Vector10d x = OnCircle(c, r, w, phi, vz);
      x.segment<3>(6) = Eigen::Vector3d(1.0, -2.0, 0.5);
      CoordinatedTurn(x, dt, next, jacobian);
      Vector10d expected = OnCircle(c, r, w, phi + w * dt, vz);
      expected(2) += vz * dt;
      INFO("w " << w << " dt " << dt << ": got " << next.transpose() << ", expected "
                << expected.transpose());
      CHECK((next - expected).norm() < 1e-9);
    }
  }
  // omega = 0: a straight line, p + v dt.
  Vector10d straight = Vector10d::Zero();
  straight.head<3>() = c;
  straight.segment<3>(3) = Eigen::Vector3d(3.0, -4.0, 1.0);
  CoordinatedTurn(straight, 0.5, next, jacobian);
  CHECK((next.head<3>() - (c + 0.5 * straight.segment<3>(3))).norm() < 1e-12);
  CHECK((next.segment<3>(3) - straight.segment<3>(3)).norm() < 1e-12);

  // The Jacobian against central differences, turning and straight (where
  // d/d omega is the limit -dt^2/2 vy, dt^2/2 vx, -dt vy, dt vx).
  for (const Vector10d& x : {OnCircle(c, 25.0, 0.3, 2.0, -0.2), straight}) {
    const double dt = 0.4, h = 1e-6;
    CoordinatedTurn(x, dt, next, jacobian);
    Matrix10d numeric;
    for (int i = 0; i < 10; ++i) {
      Vector10d up = x, down = x, f_up, f_down;
      Matrix10d unused;
      up(i) += h, down(i) -= h;
      CoordinatedTurn(up, dt, f_up, unused);
      CoordinatedTurn(down, dt, f_down, unused);
      numeric.col(i) = (f_up - f_down) / (2.0 * h);
    }
    INFO("analytic\n" << jacobian << "\nnumeric\n" << numeric);
    CHECK((jacobian - numeric).cwiseAbs().maxCoeff() < 1e-6);
  }
  CoordinatedTurn(straight, 0.4, next, jacobian);
  CHECK(jacobian(0, 9) == Approx(0.08 * 4.0));  // -dt^2/2 vy, vy = -4
  CHECK(jacobian(4, 9) == Approx(0.4 * 3.0));   // dt vx
}

TEST_CASE("AnchorFilter: the IMM coasts an orbit on its turn mode", "[pipeline]") {
  // The default scenario's orbit (6 m/s on 25 m, 1.44 m/s^2 towards the
  // centre), a LiDAR fix and a ray every 0.1 s for 20 s, noiseless; then 2 s
  // of rays alone, as when the drone is between the LiDAR's scan lines. The
  // IMM settles on its turn mode and coasts along the circle; the constant
  // acceleration filter, whose acceleration does not turn, drifts off it
  // along the ray.
  const Eigen::Vector3d centre(0.0, 0.0, 30.0);
  const double radius = 25.0, omega = 6.0 / 25.0;
  const Eigen::Vector3d eye(-30.0, -30.0, 1.5);
  const auto truth = [&](double t) -> Eigen::Vector3d {
    return OnCircle(centre, radius, omega, omega * t, 0.0).head<3>();
  };
  AnchorFilter imm(AnchorFilter::Motion::kImm), ca(AnchorFilter::Motion::kCa);
  CHECK_FALSE(imm.TurnProbability().has_value());
  for (int k = 0; k <= 220; ++k) {
    const double t = 0.1 * k;
    for (AnchorFilter* g : {&imm, &ca}) {
      g->Observe(Modality::kCamera, Ray(eye, truth(t), t));
      if (k <= 200) g->Observe(Modality::kLidar, Lidar(truth(t), t));
    }
  }
  REQUIRE(imm.TurnProbability().has_value());
  CHECK(*imm.TurnProbability() > 0.9);
  CHECK(*ca.TurnProbability() == 0.0);
  const double t = 22.0;
  const double imm_error = (CheckAt(imm, t, truth(t), 1.0).position_m - truth(t)).norm();
  const double ca_error = (CheckAt(ca, t, truth(t), 10.0).position_m - truth(t)).norm();
  INFO("after 2 s of rays alone: IMM " << imm_error << " m, CA " << ca_error << " m");
  CHECK(imm_error < 0.05);
  CHECK(ca_error > 4.0 * imm_error);
}

TEST_CASE("AnchorFilter: a manoeuvre moves the IMM to its manoeuvring mode and back",
          "[pipeline]") {
  // Straight and level at 6 m/s for 10 s, then 1 s at 5 m/s^2 (the
  // trajectories' limit) along the track, then straight again at 11 m/s; a
  // LiDAR fix and a ray every 0.1 s, noiseless. A quiet turn explains the
  // straight legs (omega 0) but not the burst: the constant-velocity mode
  // takes over during it and hands back after.
  const Eigen::Vector3d p0(40.0, -30.0, 25.0), u(0.6, 0.8, 0.0);
  const double v0 = 6.0, accel = 5.0, t1 = 10.0, t2 = 11.0;
  const auto truth = [&](double t) -> Eigen::Vector3d {
    if (t <= t1) return p0 + v0 * t * u;
    const double burst = std::min(t, t2) - t1;
    const double after = std::max(0.0, t - t2);
    return p0 +
           (v0 * t1 + v0 * burst + 0.5 * accel * burst * burst + (v0 + accel * (t2 - t1)) * after) *
               u;
  };
  AnchorFilter imm(AnchorFilter::Motion::kImm), cv(AnchorFilter::Motion::kCv);
  double steady = 0.0, in_burst = 1.0, worst_m = 0.0, cv_worst_m = 0.0;
  for (int k = 0; k <= 160; ++k) {
    const double t = 0.1 * k;
    for (AnchorFilter* g : {&imm, &cv}) {
      g->Observe(Modality::kCamera, Ray(kEye, truth(t), t));
      g->Observe(Modality::kLidar, Lidar(truth(t), t));
    }
    const std::optional<Estimate> e = imm.PredictAt(t), e_cv = cv.PredictAt(t);
    REQUIRE(e.has_value());
    REQUIRE(e_cv.has_value());
    if (k >= 20) {
      worst_m = std::max(worst_m, (e->position_m - truth(t)).norm());
      cv_worst_m = std::max(cv_worst_m, (e_cv->position_m - truth(t)).norm());
    }
    if (k == 100) steady = *imm.TurnProbability();
    if (k > 100 && k <= 110) in_burst = std::min(in_burst, *imm.TurnProbability());
  }
  INFO("turn mode: " << steady << " before, " << in_burst << " at least during, "
                     << *imm.TurnProbability() << " 5 s after; worst error " << worst_m
                     << " m (constant velocity alone " << cv_worst_m << " m)");
  CHECK(steady > 0.8);
  CHECK(in_burst < 0.3);
  CHECK(*imm.TurnProbability() > 0.8);
  // Settled (from 2 s on), the estimate at a fix stays within 0.3 m through
  // the burst, whose 2.5 m beyond constant velocity the turn mode alone
  // would lag by metres: the manoeuvring mode follows it, a few fixes late
  // (the constant-velocity filter alone: 0.11 m).
  CHECK(worst_m < 0.3);
}

}  // namespace uavsim::pipeline
