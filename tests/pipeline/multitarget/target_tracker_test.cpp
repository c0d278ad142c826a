// `mtt`'s and `mtt_jpda`'s tracker (pipeline/multitarget/target_tracker.h) on synthetic
// detections: a LiDAR at 10 Hz and a radar at 10 Hz (each a scan of every
// target, with Gaussian noise), a camera's rays at 30 Hz. Two targets that
// cross keep their labels; a target that appears mid-run gets a new track
// within M-of-N windows and the other's label is untouched; one-off clutter
// confirms no track; a lost target's track is deleted after the coast.
#include "pipeline/multitarget/target_tracker.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

namespace uavsim::pipeline {
namespace {

constexpr double kWindow = 0.2;
const Eigen::Vector3d kLidar(40.0, -30.0, 1.0), kRadar(-30.0, -30.0, 1.0), kEye(0.0, -40.0, 1.5);

using Path = std::function<std::optional<Eigen::Vector3d>(double)>;

// Crossing at t = 5 s at (0, 0, 30): one flies along +x, the other along
// +y, both at 4 m/s, 1 m apart in height at the crossing.
std::optional<Eigen::Vector3d> AlongX(double t) {
  return Eigen::Vector3d(-20.0 + 4.0 * t, 0.0, 30.0);
}
std::optional<Eigen::Vector3d> AlongY(double t) {
  return Eigen::Vector3d(0.0, -20.0 + 4.0 * t, 31.0);
}

struct Sensors {
  std::mt19937 rng{7};
  std::normal_distribution<double> noise{0.0, 1.0};

  Eigen::Vector3d Jitter(double sigma) {
    return sigma * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  }
  // What every detection of node `node` at time t carries.
  static Detection Of(core::Modality modality, int node, double t, GeometricAnchor::Kind kind) {
    Detection d;
    d.modality = modality;
    d.node = node;
    d.t_capture_s = t;
    d.anchor.kind = kind;
    d.anchor.t_s = t;
    return d;
  }
  Detection Lidar(const Eigen::Vector3d& p, double t) {
    Detection d = Of(core::Modality::kLidar, 1, t, GeometricAnchor::Kind::kPoint);
    d.anchor.origin_w = p + Jitter(0.1);
    d.anchor.sensor_w = kLidar;
    d.anchor.range_m = (d.anchor.origin_w - kLidar).norm();
    return d;
  }
  Detection Radar(const Eigen::Vector3d& p, const Eigen::Vector3d& v, double t) {
    Detection d = Of(core::Modality::kRadar, 2, t, GeometricAnchor::Kind::kPoint);
    const Eigen::Vector3d u = (p - kRadar).normalized();
    d.anchor.origin_w = p + Jitter(0.3);
    d.anchor.sensor_w = kRadar;
    d.anchor.range_m = (p - kRadar).norm() + 0.05 * noise(rng);
    d.anchor.range_rate_mps = u.dot(v) + 0.05 * noise(rng);
    d.anchor.has_range_rate = true;
    return d;
  }
  Detection Ray(const Eigen::Vector3d& p, double t) {
    Detection d = Of(core::Modality::kCamera, 0, t, GeometricAnchor::Kind::kRay);
    d.anchor.origin_w = kEye;
    d.anchor.direction_w = (p + Jitter(0.05) - kEye).normalized();
    return d;
  }
};

// The detections of window k (ending at k * kWindow) of every target alive.
std::vector<Detection> WindowDetections(std::int64_t k, const std::vector<Path>& paths,
                                        Sensors& s) {
  std::vector<Detection> out;
  const double t0 = static_cast<double>(k - 1) * kWindow;
  for (int i = 0; i < 6; ++i) {  // 30 Hz camera, 10 Hz LiDAR and radar
    const double t = t0 + i * kWindow / 6.0;
    for (const Path& path : paths) {
      const auto p = path(t);
      if (!p) continue;
      const auto later = path(t + 0.01);
      const Eigen::Vector3d v =
          later ? Eigen::Vector3d((*later - *p) / 0.01) : Eigen::Vector3d::Zero();
      out.push_back(s.Ray(*p, t));
      if (i % 3 == 0) out.push_back(s.Lidar(*p, t));
      if (i % 3 == 1) out.push_back(s.Radar(*p, v, t));
    }
  }
  return out;
}

// Runs the tracker to t_end and returns, per window, the label of the
// track nearest each target (within 1 m; 0: none) and each one's error.
struct Followed {
  std::vector<std::vector<std::uint32_t>> labels;  // [window][target]
  std::vector<std::vector<double>> errors;
  std::vector<std::size_t> confirmed;  // tracks per window
};
Followed Run(const std::vector<Path>& paths, double t_end, Sensors& s,
             TargetTracker::Association association,
             const std::function<void(std::int64_t, std::vector<Detection>&)>& extra = {}) {
  TargetTracker tracker(kWindow, association);
  Followed f;
  for (std::int64_t k = 1; k * kWindow <= t_end + 1e-9; ++k) {
    std::vector<Detection> d = WindowDetections(k, paths, s);
    if (extra) extra(k, d);
    const std::vector<TrackEstimate> tracks = tracker.OnWindow(k, d);
    const double t = static_cast<double>(k) * kWindow;
    std::vector<std::uint32_t> labels;
    std::vector<double> errors;
    for (const Path& path : paths) {
      const auto p = path(t);
      std::uint32_t best = 0;
      double best_d = 1.0;
      for (const TrackEstimate& e : tracks)
        if (p && (e.position_m - *p).norm() < best_d)
          best = e.track, best_d = (e.position_m - *p).norm();
      labels.push_back(best);
      errors.push_back(best ? best_d : -1.0);
    }
    f.labels.push_back(labels);
    f.errors.push_back(errors);
    f.confirmed.push_back(tracks.size());
  }
  return f;
}

// Every case runs both associations: GNN (`mtt`) and JPDA (`mtt_jpda`).
#define BOTH_ASSOCIATIONS \
  GENERATE(TargetTracker::Association::kGnn, TargetTracker::Association::kJpda)

TEST_CASE("mtt: two crossing targets keep their labels", "[mtt]") {
  Sensors s;
  const auto association = BOTH_ASSOCIATIONS;
  INFO("JPDA " << (association == TargetTracker::Association::kJpda));
  const Followed f = Run({AlongX, AlongY}, 10.0, s, association);
  // Confirmed within M-of-N windows (3 of 5), then followed throughout.
  for (std::size_t w = TargetTracker::kConfirmN; w < f.labels.size(); ++w) {
    INFO("window " << w + 1);
    CHECK(f.confirmed[w] == 2);
    REQUIRE(f.labels[w][0] != 0);
    REQUIRE(f.labels[w][1] != 0);
    CHECK(f.labels[w][0] == f.labels.back()[0]);  // no identity switch
    CHECK(f.labels[w][1] == f.labels.back()[1]);
    CHECK(f.errors[w][0] < 0.3);
    CHECK(f.errors[w][1] < 0.3);
  }
  CHECK(f.labels.back()[0] != f.labels.back()[1]);
}

TEST_CASE("mtt: a target appearing mid-run gets a track of its own", "[mtt]") {
  Sensors s;
  const Path late = [](double t) -> std::optional<Eigen::Vector3d> {
    if (t < 4.0) return std::nullopt;
    return Eigen::Vector3d(10.0, 10.0 - 3.0 * (t - 4.0), 25.0);
  };
  const auto association = BOTH_ASSOCIATIONS;
  INFO("JPDA " << (association == TargetTracker::Association::kJpda));
  const Followed f = Run({AlongX, late}, 8.0, s, association);
  const auto window_of = [](double t) {
    return static_cast<std::size_t>(std::lround(t / kWindow)) - 1;
  };
  for (std::size_t w = TargetTracker::kConfirmN; w < window_of(4.0); ++w)
    CHECK(f.confirmed[w] == 1);
  const std::uint32_t first = f.labels[window_of(3.8)][0];
  REQUIRE(first != 0);
  // Confirmed within N windows of its first detection.
  const std::size_t by = window_of(4.0) + TargetTracker::kConfirmN;
  for (std::size_t w = by; w < f.labels.size(); ++w) {
    INFO("window " << w + 1);
    CHECK(f.confirmed[w] == 2);
    CHECK(f.labels[w][0] == first);
    REQUIRE(f.labels[w][1] != 0);
    CHECK(f.labels[w][1] != first);
    CHECK(f.errors[w][1] < 0.3);
  }
}

TEST_CASE("mtt: one-off clutter confirms no track; a lost target's track is deleted", "[mtt]") {
  Sensors s;
  std::mt19937 clutter_rng(3);
  std::uniform_real_distribution<double> where(-50.0, 50.0);
  const Path gone = [](double t) -> std::optional<Eigen::Vector3d> {
    if (t >= 3.0) return std::nullopt;
    return AlongX(t);
  };
  // Four LiDAR points a window scattered over 100 m x 100 m x 50 m.
  const auto association = BOTH_ASSOCIATIONS;
  INFO("JPDA " << (association == TargetTracker::Association::kJpda));
  const Followed f =
      Run({gone}, 8.0, s, association, [&](std::int64_t k, std::vector<Detection>& d) {
        for (int i = 0; i < 4; ++i) {
          const double t = static_cast<double>(k - 1) * kWindow + 0.05 * i;
          d.push_back(s.Lidar(Eigen::Vector3d(where(clutter_rng), where(clutter_rng),
                                              25.0 + 0.5 * where(clutter_rng)),
                              t));
          d.back().node = 3;
        }
      });
  const auto window_of = [](double t) {
    return static_cast<std::size_t>(std::lround(t / kWindow)) - 1;
  };
  for (std::size_t w = TargetTracker::kConfirmN; w < window_of(3.0); ++w)
    CHECK(f.confirmed[w] == 1);
  // Gone at 3 s: deleted kMaxCoast_s later; clutter confirms nothing.
  for (std::size_t w = window_of(3.0 + TargetTracker::kMaxCoast_s) + 1; w < f.confirmed.size(); ++w)
    CHECK(f.confirmed[w] == 0);
}

TEST_CASE("mtt: windows must increase", "[mtt]") {
  TargetTracker tracker(kWindow);
  tracker.OnWindow(3, {});
  CHECK_THROWS_AS(tracker.OnWindow(3, {}), std::invalid_argument);
  CHECK_THROWS_AS(TargetTracker(0.0), std::invalid_argument);
}

}  // namespace
}  // namespace uavsim::pipeline

namespace uavsim::pipeline {
namespace {

TEST_CASE("AnchorFilter::UpdateWithMixture: one fix of probability 1 is the Kalman update",
          "[mtt]") {
  // The PDA update with beta = {1} moves a CV track as a plain Kalman
  // update with the position fix does: x + K (z - p), K = P H^T S^-1.
  AnchorFilter a(AnchorFilter::Motion::kCv), b(AnchorFilter::Motion::kCv);
  GeometricAnchor start;
  start.kind = GeometricAnchor::Kind::kPoint;
  start.origin_w = {1.0, 2.0, 30.0};
  start.sensor_w = {40.0, -30.0, 1.0};
  start.range_m = (start.origin_w - start.sensor_w).norm();
  start.t_s = 1.0;
  a.StartAt(core::Modality::kLidar, start);
  b.StartAt(core::Modality::kLidar, start);
  GeometricAnchor next = start;
  next.origin_w = {1.3, 2.1, 30.0};
  next.t_s = 1.1;
  REQUIRE(a.UpdateWith(core::Modality::kLidar, next));
  const auto fix = AnchorFilter::PositionFixOf(core::Modality::kLidar, next);
  REQUIRE(b.UpdateWithMixture({fix}, {1.0}, 0.9, 1e-3));
  const auto ea = a.PredictAt(1.1), eb = b.PredictAt(1.1);
  REQUIRE(ea);
  REQUIRE(eb);
  CHECK((ea->position_m - eb->position_m).norm() < 1e-9);
  CHECK((ea->velocity_mps - eb->velocity_mps).norm() < 1e-9);
  // beta = 1/2: halfway between the prediction and the update (positions).
  AnchorFilter c(AnchorFilter::Motion::kCv);
  c.StartAt(core::Modality::kLidar, start);
  const Eigen::Vector3d predicted = c.PredictAt(1.1)->position_m;
  REQUIRE(c.UpdateWithMixture({fix}, {0.5}, 0.9, 1e-3));
  CHECK((c.PredictAt(1.1)->position_m - 0.5 * (predicted + ea->position_m)).norm() < 1e-9);
  // Outside the gate: no likelihood.
  auto far = fix;
  far.position_m.x() += 50.0;
  CHECK_FALSE(c.PositionLogLikelihood(far));
  CHECK(c.PositionLogLikelihood(fix));
}

}  // namespace
}  // namespace uavsim::pipeline
