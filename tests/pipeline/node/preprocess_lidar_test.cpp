// LidarPreprocessor on synthetic scans whose truth is known by construction:
// a static scene (ground, a wall, a pole) sampled with range noise, and
// boxes of points that move through it.
#include <Eigen/Core>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "pipeline/node/lidar_preprocessor.h"

namespace uavsim::pipeline {
namespace {

// The static scene, the same surface samples every scan, each with fresh
// 2 cm noise (the LiDAR's default range noise) and sweep offsets in
// [0, 0.1) s.
std::vector<sensors::LidarPoint> StaticScene(int scan) {
  core::RngStream noise(11, "preprocess_lidar_test/scan" + std::to_string(scan));
  std::vector<sensors::LidarPoint> points;
  auto add = [&](double x, double y, double z) {
    points.push_back({static_cast<float>(x + noise.Normal(0.0, 0.02)),
                      static_cast<float>(y + noise.Normal(0.0, 0.02)),
                      static_cast<float>(z + noise.Normal(0.0, 0.02)), 0.4f,
                      static_cast<float>(noise.Uniform(0.0, 0.1))});
  };
  for (double x = 2.0; x < 40.0; x += 0.3)  // ground
    for (double y = -15.0; y < 15.0; y += 0.3) add(x, y, 0.0);
  for (double y = -15.0; y < 15.0; y += 0.25)  // a wall at x = 40
    for (double z = 0.0; z < 12.0; z += 0.25) add(40.0, y, z);
  for (double z = 0.0; z < 6.0; z += 0.1) add(20.0, 5.0, z);  // a pole
  return points;
}

// A box's surface sampled on a grid: n x n points on each of its six faces,
// intensity 0.9, t_offset 0.05 s.
std::vector<sensors::LidarPoint> Box(const Eigen::Vector3d& centre, double size_m, int n) {
  std::vector<sensors::LidarPoint> points;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          Eigen::Vector3d p;
          p[axis] = side * 0.5 * size_m;
          p[(axis + 1) % 3] = (i + 0.5) / n * size_m - 0.5 * size_m;
          p[(axis + 2) % 3] = (j + 0.5) / n * size_m - 0.5 * size_m;
          p += centre;
          points.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()),
                            static_cast<float>(p.z()), 0.9f, 0.05f});
        }
  return points;
}

sensors::PointCloudFrame Scan(int scan,
                              const std::vector<std::vector<sensors::LidarPoint>>& extra) {
  sensors::PointCloudFrame frame;
  frame.t_start_s = 0.1 * scan;
  frame.points = StaticScene(scan);
  for (const auto& e : extra) frame.points.insert(frame.points.end(), e.begin(), e.end());
  return frame;
}

bool InsideBox(const float* p, const Eigen::Vector3d& centre, double size_m) {
  for (int k = 0; k < 3; ++k)
    if (std::abs(p[k] - centre[k]) > 0.5 * size_m + 1e-4) return false;
  return true;
}

sensors::LidarConfig Sensor() {
  sensors::LidarConfig c;
  c.pose.position_m = Eigen::Vector3d(0.0, 0.0, 1.5);
  return c;
}

TEST_CASE("LidarPreprocessor: the static scene vanishes, a moving box is kept whole",
          "[pipeline]") {
  const PreprocessConfig config;
  LidarPreprocessor pre(Sensor(), config);
  const int warmup = config.lidar.warmup_frames;
  for (int k = 0; k < warmup; ++k) {
    const PointObservation obs = pre.Process(Scan(k, {}));
    CHECK(obs.count() == 0);
    CHECK(obs.channels == 4);
    CHECK(pre.warmed_up() == (k == warmup - 1));
  }
  CHECK(pre.static_voxel_count() > 1000);

  SECTION("static scan: nothing left") {
    const PointObservation obs = pre.Process(Scan(warmup, {}));
    CHECK(obs.count() == 0);
    CHECK(obs.t_s == Approx(0.1 * warmup));
  }
  SECTION("moving box") {
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d centre(10.0 + 1.5 * k, -3.0 + 0.2 * k, 8.0 - 0.3 * k);
      const std::vector<sensors::LidarPoint> box = Box(centre, 0.5, 6);
      const PointObservation obs = pre.Process(Scan(warmup + k, {box}));
      INFO("scan " << k);
      REQUIRE(obs.count() == box.size());  // 216 points
      for (std::size_t i = 0; i < obs.count(); ++i) {
        CHECK(InsideBox(&obs.values[4 * i], centre, 0.5));
        CHECK(obs.values[4 * i + 3] == 0.9f);  // intensity passes through
      }
      CHECK(obs.t_s == Approx(0.1 * (warmup + k) + 0.05));  // when the box was swept
      CHECK(obs.sensor_position_w == Eigen::Vector3d(0.0, 0.0, 1.5));
    }
  }
  SECTION("a bird's few points are a smaller cluster and are dropped") {
    const Eigen::Vector3d uav(15.0, 2.0, 6.0), bird(25.0, -6.0, 9.0);
    const PointObservation obs = pre.Process(Scan(warmup, {Box(bird, 0.2, 2), Box(uav, 0.5, 6)}));
    REQUIRE(obs.count() == 216);
    for (std::size_t i = 0; i < obs.count(); ++i) CHECK(InsideBox(&obs.values[4 * i], uav, 0.5));
  }
  SECTION("max_observations: the further clusters, largest first, each its own") {
    PreprocessConfig several = config;
    several.max_observations = 3;
    LidarPreprocessor pre3(Sensor(), several);
    for (int k = 0; k < warmup; ++k) pre3.Process(Scan(k, {}));
    const Eigen::Vector3d uav(15.0, 2.0, 6.0), uav2(5.0, 12.0, 7.0), bird(25.0, -6.0, 9.0);
    std::vector<PointObservation> further;
    // Boxes of 216, 24 and 96 points (six faces of n x n).
    const PointObservation obs = pre3.Process(
        Scan(warmup, {Box(bird, 0.2, 2), Box(uav, 0.5, 6), Box(uav2, 0.4, 4)}), &further);
    REQUIRE(obs.count() == 216);
    REQUIRE(further.size() == 2);
    REQUIRE(further[0].count() == 96);
    REQUIRE(further[1].count() == 24);
    for (std::size_t i = 0; i < 96; ++i) CHECK(InsideBox(&further[0].values[4 * i], uav2, 0.4));
    for (std::size_t i = 0; i < 24; ++i) CHECK(InsideBox(&further[1].values[4 * i], bird, 0.2));
    CHECK(further[0].sensor_position_w == obs.sensor_position_w);
    // max_observations 2 keeps the larger further one; 1 (the default) none.
    several.max_observations = 2;
    LidarPreprocessor pre2(Sensor(), several);
    for (int k = 0; k < warmup; ++k) pre2.Process(Scan(k, {}));
    pre2.Process(Scan(warmup, {Box(bird, 0.2, 2), Box(uav, 0.5, 6), Box(uav2, 0.4, 4)}), &further);
    REQUIRE(further.size() == 1);
    CHECK(further[0].count() == 96);
    pre.Process(Scan(warmup, {Box(bird, 0.2, 2), Box(uav, 0.5, 6)}), &further);
    CHECK(further.empty());
  }
  SECTION("clusters_kept 0 keeps every dynamic point") {
    PreprocessConfig all = config;
    all.lidar.clusters_kept = 0;
    LidarPreprocessor keep_all(Sensor(), all);
    for (int k = 0; k < warmup; ++k) keep_all.Process(Scan(k, {}));
    const PointObservation obs = keep_all.Process(
        Scan(warmup, {Box({25.0, -6.0, 9.0}, 0.2, 2), Box({15.0, 2.0, 6.0}, 0.5, 6)}));
    CHECK(obs.count() == 24 + 216);
  }
  SECTION("more than 1024 dynamic points: 1024, evenly spaced") {
    const std::vector<sensors::LidarPoint> box = Box({15.0, 2.0, 6.0}, 1.0, 20);  // 2400
    const PointObservation obs = pre.Process(Scan(warmup, {box}));
    REQUIRE(obs.count() == 1024);
    // The i-th kept point is the box's floor(i * 2400 / 1024)-th.
    for (std::size_t i : {std::size_t{0}, std::size_t{1}, std::size_t{517}, std::size_t{1023}}) {
      const sensors::LidarPoint& p = box[i * box.size() / 1024];
      CHECK(obs.values[4 * i + 0] == p.x_m);
      CHECK(obs.values[4 * i + 1] == p.y_m);
      CHECK(obs.values[4 * i + 2] == p.z_m);
    }
  }
}

TEST_CASE(
    "LidarPreprocessor: with an occupancy fraction, a target crossing the warm-up stays "
    "dynamic",
    "[pipeline]") {
  // Every static surface sample is in every scan here (a spinning LiDAR):
  // a fraction no passing target reaches keeps its path out of the
  // background.
  PreprocessConfig config;
  config.lidar.occupancy_threshold = 0.25;
  LidarPreprocessor pre(Sensor(), config);
  const int warmup = config.lidar.warmup_frames;
  for (int k = 0; k < warmup; ++k) {
    const Eigen::Vector3d centre(10.0 + 0.6 * k, -3.0, 8.0);
    CHECK(pre.Process(Scan(k, {Box(centre, 0.5, 6)})).count() == 0);
  }
  for (int k = 0; k < 8; ++k) {  // back along the same path
    const Eigen::Vector3d centre(10.0 + 1.5 * k, -3.0, 8.0);
    INFO("scan " << k);
    CHECK(pre.Process(Scan(warmup + k, {Box(centre, 0.5, 6)})).count() == 216);
  }
  // The default (one hit makes a voxel static) absorbs that path.
  LidarPreprocessor any_hit(Sensor(), PreprocessConfig{});
  for (int k = 0; k < warmup; ++k)
    any_hit.Process(Scan(k, {Box({10.0 + 0.6 * k, -3.0, 8.0}, 0.5, 6)}));
  CHECK(any_hit.Process(Scan(warmup, {Box({10.0, -3.0, 8.0}, 0.5, 6)})).count() == 0);
}

TEST_CASE("LidarPreprocessor: deterministic, and Reset forgets the background", "[pipeline]") {
  const PreprocessConfig config;
  std::vector<PointObservation> runs[2];
  for (auto& run : runs) {
    LidarPreprocessor pre(Sensor(), config);
    for (int k = 0; k < config.lidar.warmup_frames + 5; ++k)
      run.push_back(pre.Process(Scan(k, {Box({12.0 + k, 0.0, 7.0}, 0.5, 5)})));
  }
  for (std::size_t k = 0; k < runs[0].size(); ++k) {
    CHECK(runs[0][k].values == runs[1][k].values);
    CHECK(runs[0][k].t_s == runs[1][k].t_s);
  }
  LidarPreprocessor pre(Sensor(), config);
  for (int k = 0; k < config.lidar.warmup_frames; ++k) pre.Process(Scan(k, {}));
  REQUIRE(pre.warmed_up());
  pre.Reset();
  CHECK_FALSE(pre.warmed_up());
  CHECK(pre.static_voxel_count() == 0);
  CHECK(pre.Process(Scan(0, {Box({12.0, 0.0, 7.0}, 0.5, 5)})).count() == 0);
}

TEST_CASE("LidarPreprocessor: raw variant subsamples the whole cloud from the first scan",
          "[pipeline]") {
  PreprocessConfig config;
  config.lidar.raw = true;
  LidarPreprocessor pre(Sensor(), config);
  const sensors::PointCloudFrame frame = Scan(0, {});
  REQUIRE(frame.points.size() > 15000);
  const PointObservation obs = pre.Process(frame);
  REQUIRE(obs.count() == 1024);
  CHECK(obs.channels == 4);
  for (std::size_t i : {std::size_t{0}, std::size_t{300}, std::size_t{1023}}) {
    const sensors::LidarPoint& p = frame.points[i * frame.points.size() / 1024];
    CHECK(obs.values[4 * i + 0] == p.x_m);
    CHECK(obs.values[4 * i + 3] == p.intensity);
  }
  sensors::PointCloudFrame small;
  small.points = Box({5.0, 0.0, 2.0}, 1.0, 4);            // 96 points
  small.points.push_back({NAN, 0.0f, 0.0f, 0.5f, 0.0f});  // dropped
  CHECK(pre.Process(small).count() == 96);
  PreprocessConfig all_raw;
  all_raw.raw = true;
  CHECK(LidarPreprocessor(Sensor(), all_raw).Process(frame).count() == 1024);
}

// One return at `range_m` straight ahead (+x) of the sensor, of received
// power `power` (the LiDAR's normalised units: intensity = P * 5 m^2 at the
// default 5 m saturation range).
sensors::LidarPoint Return(double range_m, double power) {
  const sensors::LidarConfig c = Sensor();
  return {static_cast<float>(range_m), 0.0f, 1.5f,
          static_cast<float>(std::min(1.0, power * c.saturation_range_m * c.saturation_range_m)),
          0.05f};
}

// Closed forms of the LiDAR's weather echoes (sensors/lidar.h), written out
// here rather than taken from sensors/lidar_atmosphere.h: the default 1 m to
// 10 m linear overlap, 5 ns pulse.
double Overlap(double r) { return std::clamp((r - 1.0) / 9.0, 0.0, 1.0); }
double FogMean(double visibility_m, double alpha, double r) {
  const double rho_v = M_PI * (0.046 / visibility_m) * 3e8 * 5e-9 / 2.0;
  return rho_v * Overlap(r) * std::exp(-2.0 * alpha * r) / (r * r);
}

TEST_CASE("LidarPreprocessor: fog and rain echoes are dropped, hard targets kept", "[pipeline]") {
  PreprocessConfig config;
  config.lidar.weather_echo_rejection = true;
  config.lidar.clusters_kept = 0;  // every dynamic point: each return is judged alone
  const auto judge = [&](const core::WeatherConfig& w, const sensors::LidarPoint& p) {
    LidarPreprocessor pre(Sensor(), config, w);
    for (int k = 0; k < config.lidar.warmup_frames; ++k) pre.Process(sensors::PointCloudFrame{});
    sensors::PointCloudFrame frame;
    frame.points = {p};
    return pre.Process(frame).count() == 1;  // kept
  };
  core::WeatherConfig fog;
  fog.fog_visibility_m = 300.0;
  const double alpha_fog = 3.912 / 300.0;  // Kim et al.: q = 0 below 500 m
  // A fog echo's speckle fade is Gamma(M, 1/M), widest (Exp(1)) at M = 1:
  // 15 times the mean is a fog echo (kept only past 20).
  CHECK_FALSE(judge(fog, Return(8.0, 15.0 * FogMean(300.0, alpha_fog, 8.0))));
  CHECK(judge(fog, Return(8.0, 25.0 * FogMean(300.0, alpha_fog, 8.0))));
  // A drone (10 % at 905 nm, the world's drone material) at 30 m, head-on:
  // 0.1 e^{-2 alpha r} / r^2, hundreds of times the fog's mean there.
  const double drone_30 = 0.1 * std::exp(-2.0 * alpha_fog * 30.0) / 900.0;
  CHECK(drone_30 > 100.0 * FogMean(300.0, alpha_fog, 30.0));
  CHECK(judge(fog, Return(30.0, drone_30)));
  CHECK(judge(fog, Return(3.0, 10.0)));  // saturated: a hard target

  core::WeatherConfig rain;
  rain.rain_mm_h = 10.0;
  const double lambda = 4.1 * std::pow(10.0, -0.21);  // Marshall-Palmer, 1/mm
  const double alpha_rain = M_PI * 8000.0 / std::pow(lambda, 3) * 1e-6;
  // A drop filling the beam at 4 m: Fresnel 0.0199 of a white target.
  const double drop_4 = 0.0199 * Overlap(4.0) * std::exp(-2.0 * alpha_rain * 4.0) / 16.0;
  CHECK_FALSE(judge(rain, Return(4.0, drop_4)));
  CHECK_FALSE(judge(rain, Return(4.0, 0.3 * drop_4)));
  CHECK(judge(rain, Return(4.0, 2.0 * drop_4)));

  // In clear air, and with the switch off, nothing is a weather echo.
  CHECK(judge(core::WeatherConfig{}, Return(8.0, 15.0 * FogMean(300.0, alpha_fog, 8.0))));
  config.lidar.weather_echo_rejection = false;
  CHECK(judge(fog, Return(8.0, FogMean(300.0, alpha_fog, 8.0))));
  CHECK(judge(rain, Return(4.0, drop_4)));
}

}  // namespace
}  // namespace uavsim::pipeline

namespace uavsim::pipeline {
namespace {

PreprocessConfig SurveyConfig() {
  PreprocessConfig config;
  config.lidar.background = LidarBackground::kSurvey;
  return config;
}

// A survey of five scans of the static scene alone (scans -5 .. -1).
std::shared_ptr<const LidarPreprocessor::StaticMap> SurveyOf(const LidarPreprocessor& pre) {
  auto map = std::make_shared<LidarPreprocessor::StaticMap>();
  for (int k = -5; k < 0; ++k) pre.AddSurveyScan(Scan(k, {}), *map);
  return map;
}

TEST_CASE("LidarPreprocessor survey: a prior map, the target reported from the first scan",
          "[pipeline]") {
  LidarPreprocessor pre(Sensor(), SurveyConfig());
  CHECK_THROWS_AS(pre.Process(Scan(0, {})), std::logic_error);  // no map yet
  pre.SetStaticMap(SurveyOf(pre));
  CHECK(pre.warmed_up());
  CHECK(pre.static_voxel_count() > 1000);
  // The first scan already: the static scene gone, a passing box kept whole,
  // including where the box is on the frame where warm-up would learn it.
  const Eigen::Vector3d centre(12.0, 1.0, 5.0);
  const std::vector<sensors::LidarPoint> box = Box(centre, 0.5, 6);
  const PointObservation first = pre.Process(Scan(0, {box}));
  REQUIRE(first.count() == box.size());
  for (std::size_t i = 0; i < first.count(); ++i)
    CHECK(InsideBox(&first.values[4 * i], centre, 0.5));
  // Back at the same place later: still kept (a warm-up background would
  // have learnt the box's voxels during its first scans).
  CHECK(pre.Process(Scan(1, {})).count() == 0);
  CHECK(pre.Process(Scan(2, {box})).count() == box.size());
  // Reset keeps the surveyed map.
  pre.Reset();
  CHECK(pre.warmed_up());
  CHECK(pre.Process(Scan(3, {box})).count() == box.size());
}

TEST_CASE("LidarPreprocessor survey: a parked car that came after the survey stays dynamic",
          "[pipeline]") {
  PreprocessConfig config = SurveyConfig();
  const bool gate = GENERATE(false, true);
  config.lidar.drone_gate = gate;
  LidarPreprocessor pre(Sensor(), config);
  pre.SetStaticMap(SurveyOf(pre));
  // A 2 m box (a parked car) on the ground at 25 m from scan 0 on: not in
  // the map, so its points are dynamic in every scan. Without the drone
  // gate, as the largest cluster it is what the node sends; with it, it is
  // no candidate (its 3.5 m diagonal is more than a 1 m drone smeared by
  // 20 m/s over a 0.1 s scan, and its 864 points more than 4 x the 15 a
  // 1 m square returns at 25 m from this spinning LiDAR: 57 600 rays over
  // 2 pi (sin 45 deg + sin 15 deg) sr), and a drone-sized box flying by at
  // the same time is sent instead.
  const Eigen::Vector3d car(25.0, -6.0, 1.0);
  const std::vector<sensors::LidarPoint> parked = Box(car, 2.0, 12);
  for (int k = 0; k < 10; ++k) {
    const PointObservation obs = pre.Process(Scan(k, {parked}));
    INFO("scan " << k << ", gate " << gate);
    if (gate) {
      CHECK(obs.count() == 0);
    } else {
      REQUIRE(obs.count() > 0);
      CHECK(InsideBox(&obs.values[0], car, 2.0));
    }
  }
  const Eigen::Vector3d drone(12.0, 3.0, 6.0);
  const std::vector<sensors::LidarPoint> small = Box(drone, 0.5, 5);  // 150 points
  const PointObservation obs = pre.Process(Scan(10, {parked, small}));
  REQUIRE(obs.count() > 0);
  CHECK(InsideBox(&obs.values[0], gate ? drone : car, gate ? 0.5 : 2.0));
}

TEST_CASE("LidarPreprocessor drone gate: a drone-sized cluster passes at any range it returns",
          "[pipeline]") {
  PreprocessConfig config = SurveyConfig();
  config.lidar.drone_gate = true;
  LidarPreprocessor pre(Sensor(), config);
  pre.SetStaticMap(SurveyOf(pre));
  // A 0.5 m box with 5 x 5 points a face (150) 13.2 m from the sensor, 2 x 2
  // (24) at 30.7 m: fewer than 4 x a 1 m square's returns there (4 x 55 and
  // 4 x 10).
  int k = 0;
  for (const auto& [centre, n] : {std::pair{Eigen::Vector3d(12.0, 3.0, 6.0), 5},
                                  std::pair{Eigen::Vector3d(0.0, 30.0, 8.0), 2}}) {
    const std::vector<sensors::LidarPoint> box = Box(centre, 0.5, n);
    const PointObservation obs = pre.Process(Scan(k++, {box}));
    INFO("at " << centre.transpose());
    CHECK(obs.count() == box.size());
  }
  // The same box smeared along 4 m in one scan (a drone at 40 m/s) is not.
  std::vector<sensors::LidarPoint> smeared;
  for (int i = 0; i < 9; ++i) {
    const auto part = Box(Eigen::Vector3d(12.0 + 0.5 * i, 3.0, 6.0), 0.5, 2);
    smeared.insert(smeared.end(), part.begin(), part.end());
  }
  CHECK(pre.Process(Scan(k, {smeared})).count() == 0);
}

TEST_CASE("LidarPreprocessor: SetStaticMap needs background \"survey\"", "[pipeline]") {
  LidarPreprocessor pre(Sensor(), PreprocessConfig{});
  CHECK_THROWS_AS(pre.SetStaticMap(std::make_shared<LidarPreprocessor::StaticMap>()),
                  std::logic_error);
}

}  // namespace
}  // namespace uavsim::pipeline
