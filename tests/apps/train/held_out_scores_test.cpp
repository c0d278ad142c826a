// The classical methods on held-out episodes (apps/train/held_out_scores.h): a
// target flying straight at constant speed, seen by a LiDAR whose points lie
// around it and a stereo camera whose rays meet on it, must be tracked to
// centimetres at each window's end (a filter asked at the window's start
// would be off by speed x t^w = 0.64 m); the counted windows follow
// Evaluation's rules.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "apps/train/held_out_scores.h"
#include "pipeline/training/dataset.h"
#include "sim/scenario.h"

namespace {

using uavsim::pipeline::Episode;
using uavsim::pipeline::Modality;
using uavsim::pipeline::Sample;

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";

constexpr int kWindows = 50;  // 10 s of 0.2 s windows
const Eigen::Vector3d kStart(30.0, 10.0, 40.0);
const Eigen::Vector3d kVelocity(3.0, -1.0, 0.5);  // 3.2 m/s

Eigen::Vector3d TruthAt(double t) { return kStart + kVelocity * t; }

std::uint32_t NodeOf(const uavsim::sim::Scenario& s, uavsim::sensors::SensorType type) {
  std::uint32_t i = 0;
  while (s.nodes[i].sensor.type != type) ++i;
  return i;
}

// From `first_s` on: LiDAR scans at 10 Hz, four points around the target;
// stereo camera frames at 15 Hz, both eyes' rays through the target.
Episode StraightFlight(const uavsim::sim::Scenario& s, double first_s) {
  const std::uint32_t lidar = NodeOf(s, uavsim::sensors::SensorType::kLidar);
  const std::uint32_t camera = NodeOf(s, uavsim::sensors::SensorType::kFisheyeStereo);
  Episode ep;
  ep.window_s = 0.2;
  for (int k = 1; k <= kWindows; ++k) ep.window_truth.push_back(TruthAt(0.2 * k));
  std::vector<Sample> lidar_samples, camera_samples;
  for (double t = first_s; t < 0.2 * kWindows; t += 0.1) {
    Sample sample;
    sample.modality = Modality::kLidar;
    sample.node = lidar;
    sample.t_s = t;
    sample.on_time = true;
    sample.truth_m = TruthAt(t);
    uavsim::pipeline::PointObservation o;
    o.t_s = t;
    o.channels = 4;
    o.sensor_position_w = s.nodes[lidar].sensor.lidar.pose.position_m;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d p =
          TruthAt(t) + 0.05 * Eigen::Vector3d(i % 2 ? 1 : -1, i < 2 ? 1 : -1, 0);
      o.values.insert(o.values.end(), {static_cast<float>(p.x()), static_cast<float>(p.y()),
                                       static_cast<float>(p.z()), 1.0f});
    }
    sample.points = o;
    ep.samples.push_back(sample);
  }
  const Eigen::Vector3d eye = s.nodes[camera].sensor.fisheye.pose.position_m;
  for (double t = first_s + 0.02; t < 0.2 * kWindows; t += 1.0 / 15.0) {
    Sample sample;
    sample.modality = Modality::kCamera;
    sample.node = camera;
    sample.t_s = t;
    sample.on_time = true;
    sample.truth_m = TruthAt(t);
    uavsim::pipeline::CameraObservation o;
    o.t_s = t;
    o.detected = true;
    o.eye_left_w = eye;
    o.eye_right_w = eye + Eigen::Vector3d(0.0, -0.2, 0.0);
    o.bearing_left_w = (TruthAt(t) - o.eye_left_w).normalized();
    o.bearing_right_w = (TruthAt(t) - o.eye_right_w).normalized();
    sample.camera = o;
    ep.samples.push_back(sample);
  }
  std::stable_sort(ep.samples.begin(), ep.samples.end(),
                   [](const Sample& a, const Sample& b) { return a.t_s < b.t_s; });
  return ep;
}

}  // namespace

TEST_CASE("Held-out scores: the classical methods track a straight flight at each window's end",
          "[sim][train]") {
  const uavsim::sim::Scenario s = uavsim::sim::LoadScenario(kDefault);
  const auto scores = uavsim::sim::ScoreClassicalMethods(s, {StraightFlight(s, 0.01)});
  REQUIRE(scores.size() == 2);
  const auto& ekf = scores.at("ekf");
  const auto& track = scores.at("anchor_track");
  REQUIRE(ekf.rmse_m.size() == 7);
  REQUIRE(track.rmse_m.size() == 7);
  // The EKF from the LiDAR's centroids with or without the stereo rays; the
  // anchor filter starts a track only at a ranging fix on the camera's ray.
  for (const auto& [ev, subset] :
       {std::pair{&ekf, "all"}, std::pair{&ekf, "camera+lidar"}, std::pair{&ekf, "lidar"},
        std::pair{&track, "all"}, std::pair{&track, "camera+lidar"}}) {
    INFO((ev == &ekf ? "ekf " : "anchor_track ") << subset);
    // Answers once its track is confirmed (a few frames), then every window.
    CHECK(ev->windows.at(subset) >= kWindows - 10);
    CHECK(ev->windows.at(subset) <= kWindows);
    CHECK(ev->rmse_m.at(subset) < 0.15);
  }
  // The subsets with radar see what those without it see (no radar here).
  for (const auto* ev : {&ekf, &track}) {
    CHECK(ev->windows.at("camera+radar") == ev->windows.at("camera"));
    CHECK(ev->windows.at("lidar+radar") == ev->windows.at("lidar"));
    CHECK(ev->windows.at("radar") == 0);
    CHECK(std::isnan(ev->rmse_m.at("radar")));
  }
  // Neither confirms a track without a ranging fix (the camera alone), nor
  // does the anchor filter start one without a ray (the LiDAR alone).
  CHECK(ekf.windows.at("camera") == 0);
  CHECK(track.windows.at("camera") == 0);
  CHECK(track.windows.at("lidar") == 0);
}

TEST_CASE("Held-out scores: windows count from the first arrival and in their part only",
          "[sim][train]") {
  const uavsim::sim::Scenario s = uavsim::sim::LoadScenario(kDefault);
  // Nothing arrives before 4 s (window 21): the windows before are not counted.
  Episode late = StraightFlight(s, 4.01);
  auto scores = uavsim::sim::ScoreClassicalMethods(s, {late});
  for (const char* method : {"ekf", "anchor_track"}) {
    INFO(method);
    CHECK(scores.at(method).windows.at("all") <= kWindows - 20);
    CHECK(scores.at(method).windows.at("all") >= kWindows - 30);
  }
  // Windows of another part (a frame split) are not counted; those of this
  // one are, once answered.
  Episode part = StraightFlight(s, 0.01);
  part.scored_windows.assign(kWindows, 0);
  for (int k = 31; k <= kWindows; ++k) part.scored_windows[k - 1] = 1;
  scores = uavsim::sim::ScoreClassicalMethods(s, {part});
  for (const char* method : {"ekf", "anchor_track"}) {
    INFO(method);
    const uavsim::pipeline::Evaluation& ev = scores.at(method);
    CHECK(ev.windows.at("all") == 20);
    // Each counted window's error, keyed (episode, k - 1): windows 31..50.
    const auto& per_window = ev.squared_error_m2.at("all");
    REQUIRE(per_window.size() == 20);
    CHECK(per_window.begin()->first == std::pair<std::size_t, std::int64_t>{0, 30});
    CHECK(per_window.rbegin()->first == std::pair<std::size_t, std::int64_t>{0, kWindows - 1});
    double sum = 0.0;
    for (const auto& [window, e] : per_window) sum += e;
    CHECK(std::sqrt(sum / 20.0) == Approx(ev.rmse_m.at("all")));
  }
  // Samples that arrived late are not the heads' inputs, nor these methods'.
  Episode lost = StraightFlight(s, 0.01);
  for (Sample& sample : lost.samples) sample.on_time = false;
  scores = uavsim::sim::ScoreClassicalMethods(s, {lost});
  for (const char* method : {"ekf", "anchor_track"})
    CHECK(scores.at(method).windows.at("all") == 0);
  // A sample from a node the scenario does not have is refused.
  Episode wrong = StraightFlight(s, 0.01);
  wrong.samples.front().node = static_cast<std::uint32_t>(s.nodes.size());
  CHECK_THROWS_AS(uavsim::sim::ScoreClassicalMethods(s, {wrong}), std::invalid_argument);
}
