// RadarPreprocessor and the DBSCAN it uses: clusters known by construction,
// and DBSCAN against a brute-force implementation of its definition.
#include <Eigen/Core>
#include <algorithm>
#include <catch2/catch.hpp>
#include <map>
#include <vector>

#include "core/interrupt.h"
#include "core/rng.h"
#include "pipeline/node/point_clustering.h"
#include "pipeline/node/radar_preprocessor.h"

namespace uavsim::pipeline {
namespace {

// n detections scattered (0.3 m) around `centre`, all at `velocity_mps`.
std::vector<sensors::RadarPoint> Cluster(const Eigen::Vector3d& centre, int n, double velocity_mps,
                                         core::RngStream& rng) {
  std::vector<sensors::RadarPoint> points;
  for (int i = 0; i < n; ++i)
    points.push_back({static_cast<float>(centre.x() + rng.Normal(0.0, 0.3)),
                      static_cast<float>(centre.y() + rng.Normal(0.0, 0.3)),
                      static_cast<float>(centre.z() + rng.Normal(0.0, 0.3)),
                      static_cast<float>(velocity_mps), static_cast<float>(15.0 + i % 7)});
  return points;
}

// Interleaves the clusters' points (radar detections come in range order,
// not cluster by cluster).
sensors::RadarFrame Frame(const std::vector<std::vector<sensors::RadarPoint>>& clusters) {
  sensors::RadarFrame frame;
  frame.t_capture_s = 1.25;
  for (std::size_t i = 0;; ++i) {
    bool any = false;
    for (const auto& c : clusters)
      if (i < c.size()) frame.points.push_back(c[i]), any = true;
    if (!any) break;
  }
  return frame;
}

bool Near(const float* p, const Eigen::Vector3d& centre, double radius_m) {
  return (Eigen::Vector3d(p[0], p[1], p[2]) - centre).norm() < radius_m;
}

// The paper's selection: the largest clusters, frame by frame.
PreprocessConfig Largest() {
  PreprocessConfig c;
  c.radar.selection = RadarSelection::kLargest;
  return c;
}

sensors::FmcwRadarConfig Sensor() {
  sensors::FmcwRadarConfig c;
  c.pose.position_m = Eigen::Vector3d(-20.0, 5.0, 2.0);
  return c;
}

TEST_CASE("RadarPreprocessor: of clusters of 30 and 5 points, the 30 are kept", "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/30_5");
  const Eigen::Vector3d uav(20.0, 10.0, 30.0), bird(12.0, 18.0, 25.0);
  const auto uav_points = Cluster(uav, 30, -4.0, rng);
  const auto bird_points = Cluster(bird, 5, 2.0, rng);
  RadarPreprocessor pre(Sensor(), Largest());
  // The bird first: order must not matter.
  const PointObservation obs = pre.Process(Frame({bird_points, uav_points}));
  CHECK(obs.channels == 5);
  CHECK(obs.t_s == 1.25);
  CHECK(obs.sensor_position_w == Eigen::Vector3d(-20.0, 5.0, 2.0));
  REQUIRE(obs.count() == 30);
  for (std::size_t i = 0; i < obs.count(); ++i) {
    CHECK(Near(&obs.values[5 * i], uav, 2.0));
    CHECK(obs.values[5 * i + 3] == -4.0f);  // radial velocity passes through
    CHECK(obs.values[5 * i + 4] >= 15.0f);  // SNR too
  }
}

TEST_CASE("RadarPreprocessor: max_observations sends the further clusters, each its own",
          "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/further");
  const Eigen::Vector3d uav(20.0, 10.0, 30.0), uav2(-5.0, 30.0, 35.0), bird(12.0, 18.0, 25.0);
  const auto frame =
      Frame({Cluster(bird, 5, 2.0, rng), Cluster(uav, 30, -4.0, rng), Cluster(uav2, 12, 3.0, rng)});
  PreprocessConfig config = Largest();
  config.max_observations = 3;
  std::vector<PointObservation> further;
  const PointObservation obs = RadarPreprocessor(Sensor(), config).Process(frame, &further);
  REQUIRE(obs.count() == 30);
  REQUIRE(further.size() == 2);
  REQUIRE(further[0].count() == 12);
  REQUIRE(further[1].count() == 5);
  for (std::size_t i = 0; i < 12; ++i) CHECK(further[0].values[5 * i + 3] == 3.0f);
  for (std::size_t i = 0; i < 5; ++i) CHECK(Near(&further[1].values[5 * i], bird, 2.0));
  CHECK(further[1].t_s == 1.25);
  // Without `further`, or at the default, the same observation and none further.
  const PointObservation alone = RadarPreprocessor(Sensor(), config).Process(frame);
  CHECK(alone.values == obs.values);
  RadarPreprocessor(Sensor(), Largest()).Process(frame, &further);
  CHECK(further.empty());
}

TEST_CASE("RadarPreprocessor: velocity separates co-located clusters when weighted", "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/velocity");
  const Eigen::Vector3d here(20.0, 10.0, 30.0);
  const auto fast = Cluster(here, 12, -6.0, rng);
  const auto slow = Cluster(here, 8, 1.0, rng);
  PreprocessConfig config = Largest();
  CHECK(RadarPreprocessor(Sensor(), config).Process(Frame({fast, slow})).count() == 20);
  config.radar.velocity_weight_s = 1.0;  // 7 m/s apart: 7 m in feature space
  const PointObservation obs = RadarPreprocessor(Sensor(), config).Process(Frame({fast, slow}));
  REQUIRE(obs.count() == 12);
  for (std::size_t i = 0; i < obs.count(); ++i) CHECK(obs.values[5 * i + 3] == -6.0f);
}

TEST_CASE("RadarPreprocessor: at most 1024 points, raw keeps every detection", "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/cap");
  const auto big = Cluster({30.0, 0.0, 20.0}, 3000, -3.0, rng);
  RadarPreprocessor pre(Sensor(), Largest());
  const PointObservation obs = pre.Process(Frame({big}));
  REQUIRE(obs.count() == 1024);
  for (std::size_t i : {std::size_t{0}, std::size_t{700}, std::size_t{1023}})
    CHECK(obs.values[5 * i] == big[i * big.size() / 1024].x_m);

  PreprocessConfig raw = Largest();
  raw.radar.raw = true;
  const auto a = Cluster({20.0, 10.0, 30.0}, 60, -4.0, rng);
  const auto b = Cluster({-10.0, 40.0, 15.0}, 40, 2.0, rng);
  const sensors::RadarFrame frame = Frame({a, b});
  const PointObservation all = RadarPreprocessor(Sensor(), raw).Process(frame);
  REQUIRE(all.count() == 100);
  for (std::size_t i = 0; i < all.count(); ++i) CHECK(all.values[5 * i] == frame.points[i].x_m);
  CHECK(RadarPreprocessor(Sensor(), raw).Process(Frame({big})).count() == 1024);
  CHECK(RadarPreprocessor(Sensor(), raw).Process(sensors::RadarFrame{}).count() == 0);
}

TEST_CASE("RadarPreprocessor: deterministic", "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/determinism");
  const sensors::RadarFrame frame =
      Frame({Cluster({5.0, 5.0, 5.0}, 20, 1.0, rng), Cluster({9.0, 5.0, 5.0}, 20, 1.0, rng),
             Cluster({40.0, 5.0, 5.0}, 7, 1.0, rng)});
  RadarPreprocessor pre(Sensor(), Largest());
  CHECK(pre.Process(frame).values == pre.Process(frame).values);
  CHECK(RadarPreprocessor(Sensor(), Largest()).Process(frame).values == pre.Process(frame).values);
}

// A target moving 0.5 m a frame beside clutter that lands somewhere else
// every frame, as rain clutter and noise detections do.
TEST_CASE("RadarPreprocessor: persistent keeps the cluster seen frame after frame", "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/persistent");
  PreprocessConfig config;
  config.radar.selection = RadarSelection::kPersistent;
  RadarPreprocessor persistent(Sensor(), config);
  RadarPreprocessor largest(Sensor(), Largest());
  int persistent_on_target = 0, largest_on_target = 0, sent_first = -1;
  for (int k = 0; k < 12; ++k) {
    const Eigen::Vector3d uav(20.0 + 0.5 * k, 10.0, 30.0);
    // 6 points of clutter, more than the target's 4, never twice near one place.
    const Eigen::Vector3d clutter(rng.Uniform(-40, 40), rng.Uniform(20, 60), rng.Uniform(5, 40));
    sensors::RadarFrame frame = Frame({Cluster(clutter, 6, 3.0, rng), Cluster(uav, 4, -2.0, rng)});
    frame.t_capture_s = k / 15.0;
    const PointObservation p = persistent.Process(frame);
    const PointObservation l = largest.Process(frame);
    if (p.count() > 0 && sent_first < 0) sent_first = k;
    if (p.count() > 0 && Near(&p.values[0], uav, 2.0)) ++persistent_on_target;
    if (l.count() > 0 && Near(&l.values[0], uav, 2.0)) ++largest_on_target;
  }
  CHECK(largest_on_target == 0);  // the paper's rule follows the clutter
  CHECK(sent_first == 1);         // nothing has support in the first frame
  CHECK(persistent_on_target == 11);
}

// The detections of `points` with every SNR set to `snr_db`, one raised to `peak_db`.
std::vector<sensors::RadarPoint> WithSnr(std::vector<sensors::RadarPoint> points, double snr_db,
                                         double peak_db) {
  for (sensors::RadarPoint& p : points) p.snr_db = static_cast<float>(snr_db);
  points[points.size() / 2].snr_db = static_cast<float>(peak_db);
  return points;
}

TEST_CASE(
    "RadarPreprocessor: min_peak_snr_db sends a candidate whose strongest detection "
    "reaches it, else nothing",
    "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/min_peak_snr");
  const Eigen::Vector3d uav(20.0, 10.0, 30.0), clutter(-5.0, 30.0, 35.0);
  // Rain clutter: many detections just over the CFAR; the drone: few, one strong.
  const auto clutter_points = WithSnr(Cluster(clutter, 20, 3.0, rng), 4.8, 5.5);
  const auto uav_points = WithSnr(Cluster(uav, 6, -4.0, rng), 6.0, 9.0);
  const sensors::RadarFrame frame = Frame({clutter_points, uav_points});
  PreprocessConfig config = Largest();
  config.radar.min_peak_snr_db = 5.5;  // the clutter's peak exactly: kept
  CHECK(RadarPreprocessor(Sensor(), config).Process(frame).count() == 20);
  config.radar.min_peak_snr_db = 5.6;  // the largest scores too low: nothing, not the next
  CHECK(RadarPreprocessor(Sensor(), config).Process(frame).count() == 0);
  config.radar.min_peak_snr_db = 0.0;  // off: the paper's largest
  CHECK(RadarPreprocessor(Sensor(), config).Process(frame).count() == 20);
  // With further observations the ones that score enough are sent, in order.
  config.max_observations = 2;
  config.radar.min_peak_snr_db = 8.0;
  std::vector<PointObservation> further;
  const PointObservation obs = RadarPreprocessor(Sensor(), config).Process(frame, &further);
  REQUIRE(obs.count() == 6);
  CHECK(Near(&obs.values[0], uav, 2.0));
  CHECK(further.empty());
}

TEST_CASE("RadarPreprocessor: min_peak_snr_db leaves the persistent selection's memory alone",
          "[pipeline]") {
  // Frame by frame, the gated node sends what the ungated one sends or
  // nothing, and nothing exactly when that candidate's peak is below the floor.
  core::RngStream rng(3, "preprocess_radar_test/min_peak_snr_memory");
  PreprocessConfig config;
  config.radar.selection = RadarSelection::kPersistent;
  RadarPreprocessor open(Sensor(), config);
  config.radar.min_peak_snr_db = 8.0;
  RadarPreprocessor gated(Sensor(), config);
  int dropped = 0, sent = 0;
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector3d uav(20.0 + 0.5 * k, 10.0, 30.0);
    const Eigen::Vector3d clutter(rng.Uniform(-40, 40), rng.Uniform(20, 60), rng.Uniform(5, 40));
    const double uav_peak = rng.Uniform(5.0, 11.0);  // the drone fades in and out
    sensors::RadarFrame frame = Frame({WithSnr(Cluster(clutter, 6, 3.0, rng), 5.0, 6.0),
                                       WithSnr(Cluster(uav, 4, -2.0, rng), 5.0, uav_peak)});
    frame.t_capture_s = k / 15.0;
    const PointObservation a = open.Process(frame), b = gated.Process(frame);
    if (a.count() == 0) {
      CHECK(b.count() == 0);
      continue;
    }
    double peak = 0.0;
    for (std::size_t i = 0; i < a.count(); ++i) peak = std::max(peak, double(a.values[5 * i + 4]));
    INFO("frame " << k << ", peak " << peak);
    if (peak >= 8.0) {
      CHECK(b.values == a.values);
      ++sent;
    } else {
      CHECK(b.count() == 0);
      ++dropped;
    }
  }
  CHECK(sent > 5);  // both branches were exercised
  CHECK(dropped > 5);
}

TEST_CASE("RadarPreprocessor: persistent's gate grows with the time apart", "[pipeline]") {
  core::RngStream rng(3, "preprocess_radar_test/gate");
  PreprocessConfig config;
  config.radar.selection = RadarSelection::kPersistent;
  config.radar.gate_m = 1.0;
  config.radar.max_speed_mps = 10.0;
  RadarPreprocessor pre(Sensor(), config);
  sensors::RadarFrame a = Frame({Cluster({20, 10, 30}, 5, -2.0, rng)});
  a.t_capture_s = 0.0;
  CHECK(pre.Process(a).count() == 0);
  // 0.1 s later, 3 m away: beyond 1 + 10 * 0.1 = 2 m, no support.
  sensors::RadarFrame b = Frame({Cluster({23, 10, 30}, 5, -2.0, rng)});
  b.t_capture_s = 0.1;
  CHECK(pre.Process(b).count() == 0);
  // 0.2 s after a and 2 m from it (within 3 m), 1 m from b: supported twice.
  sensors::RadarFrame c = Frame({Cluster({22, 10, 30}, 5, -2.0, rng)});
  c.t_capture_s = 0.2;
  config.radar.min_support = 2;
  RadarPreprocessor strict(Sensor(), config);
  CHECK(strict.Process(a).count() == 0);
  CHECK(strict.Process(b).count() == 0);
  CHECK(strict.Process(c).count() == 5);
  pre.Reset();
  CHECK(pre.Process(c).count() == 0);  // Reset forgot a and b
}

// Drops falling at 2 to 9.65 m/s seen straight up approach at that speed;
// seen sideways (u_z = 0) they do not move radially.
TEST_CASE("RadarPreprocessor: in rain, detections moving as falling drops are dropped",
          "[pipeline]") {
  PreprocessConfig config = Largest();
  config.radar.rain_doppler_rejection = true;
  config.radar.clusters_kept = 0;  // every detection: each is judged alone
  core::WeatherConfig rain;
  rain.rain_mm_h = 10.0;
  const auto kept = [&](const core::WeatherConfig& w, float x, float y, float z, float v) {
    sensors::RadarFrame frame;
    frame.points = {{x, y, z, v, 20.0f}};
    return RadarPreprocessor(Sensor(), config, w).Process(frame).count() == 1;
  };
  // The sensor is at (-20, 5, 2): (-20, 5, 32) is straight above it.
  CHECK_FALSE(kept(rain, -20, 5, 32, -5.0f));
  CHECK_FALSE(kept(rain, -20, 5, 32, -9.9f));  // 9.65 + the 0.5 m/s margin
  CHECK(kept(rain, -20, 5, 32, -10.3f));
  CHECK(kept(rain, -20, 5, 32, -1.3f));  // slower than a 0.5 mm drop
  CHECK(kept(rain, -20, 5, 32, 3.0f));   // receding
  // 45 degrees up: the band is -6.82 .. -1.41 m/s, widened by 0.5.
  CHECK_FALSE(kept(rain, 10, 5, 32, -4.0f));
  CHECK(kept(rain, 10, 5, 32, -7.5f));
  CHECK(kept(core::WeatherConfig{}, -20, 5, 32, -5.0f));  // clear air
  config.radar.rain_doppler_rejection = false;
  CHECK(kept(rain, -20, 5, 32, -5.0f));
}

// DBSCAN by its definition, O(n^2): core points, their eps-connected
// components, border points.
struct Reference {
  std::vector<bool> core;
  std::vector<int> component;  // of core points; -1 otherwise
};

Reference BruteForce(const std::vector<float>& xyz, double eps, int min_points) {
  const std::size_t n = xyz.size() / 3;
  auto close = [&](std::size_t a, std::size_t b) {
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k)
      d2 += (xyz[3 * a + k] - xyz[3 * b + k]) * (xyz[3 * a + k] - xyz[3 * b + k]);
    return d2 < eps * eps;
  };
  Reference r;
  r.core.assign(n, false);
  r.component.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    int count = 0;
    for (std::size_t j = 0; j < n; ++j) count += close(i, j);
    r.core[i] = count >= min_points;
  }
  int next = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!r.core[i] || r.component[i] >= 0) continue;
    std::vector<std::size_t> stack{i};
    r.component[i] = next;
    while (!stack.empty()) {
      const std::size_t a = stack.back();
      stack.pop_back();
      for (std::size_t b = 0; b < n; ++b)
        if (r.core[b] && r.component[b] < 0 && close(a, b))
          r.component[b] = next, stack.push_back(b);
    }
    ++next;
  }
  return r;
}

TEST_CASE("Dbscan: matches the definition, brute force", "[pipeline]") {
  core::RngStream rng(5, "preprocess_radar_test/dbscan");
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<float> xyz;
    for (int c = 0; c < 6; ++c) {  // blobs of various sizes plus uniform clutter
      const Eigen::Vector3d centre(rng.Uniform(0, 30), rng.Uniform(0, 30), rng.Uniform(0, 10));
      const int n = 3 + static_cast<int>(rng.UniformInt(40));
      for (int i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k)
          xyz.push_back(static_cast<float>(centre[k] + rng.Normal(0.0, 0.6)));
    }
    for (int i = 0; i < 80; ++i)
      for (double hi : {30.0, 30.0, 10.0}) xyz.push_back(static_cast<float>(rng.Uniform(0.0, hi)));
    const double eps = 1.0;
    const int min_points = 4;
    const Reference ref = BruteForce(xyz, eps, min_points);
    const DbscanClusters got = Dbscan(xyz, 3, eps, min_points);
    const std::size_t n = xyz.size() / 3;
    REQUIRE(got.label.size() == n);
    // Core points: the same partition (a bijection between component ids).
    std::map<int, int> to_ref, from_ref;
    for (std::size_t i = 0; i < n; ++i) {
      if (!ref.core[i]) continue;
      REQUIRE(got.label[i] >= 0);
      const auto [a, a_new] = to_ref.emplace(got.label[i], ref.component[i]);
      const auto [b, b_new] = from_ref.emplace(ref.component[i], got.label[i]);
      CHECK(a->second == ref.component[i]);
      CHECK(b->second == got.label[i]);
    }
    // Non-core points: noise unless within eps of a core point of their
    // cluster.
    for (std::size_t i = 0; i < n; ++i) {
      if (ref.core[i]) continue;
      bool reachable = false, joins_a_neighbour = false;
      for (std::size_t j = 0; j < n; ++j) {
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k)
          d2 += (xyz[3 * i + k] - xyz[3 * j + k]) * (xyz[3 * i + k] - xyz[3 * j + k]);
        if (ref.core[j] && d2 < eps * eps) {
          reachable = true;
          joins_a_neighbour = joins_a_neighbour || got.label[i] == got.label[j];
        }
      }
      CHECK((got.label[i] >= 0) == reachable);
      CHECK(joins_a_neighbour == reachable);
    }
    std::vector<std::size_t> sizes(got.size.size(), 0);
    for (int l : got.label)
      if (l >= 0) ++sizes[l];
    CHECK(sizes == got.size);
  }
  CHECK(Dbscan({}, 3, 1.0, 1).label.empty());
  CHECK_THROWS_WITH(Dbscan({1.0f, 2.0f}, 3, 1.0, 1), Catch::Contains("multiple of dims"));
}

TEST_CASE("LargestClusters and EvenlySpacedIndices", "[pipeline]") {
  DbscanClusters c;
  c.size = {5, 9, 5, 2, 9};
  CHECK(LargestClusters(c, 1) == std::vector<int>{1});
  CHECK(LargestClusters(c, 3) == std::vector<int>{1, 4, 0});
  CHECK(LargestClusters(c, 10) == std::vector<int>{1, 4, 0, 2, 3});
  CHECK(EvenlySpacedIndices(3, 5) == std::vector<std::size_t>{0, 1, 2});
  CHECK(EvenlySpacedIndices(10, 4) == std::vector<std::size_t>{0, 2, 5, 7});
}

}  // namespace

TEST_CASE("Dbscan: a termination request stops a large clustering", "[pipeline]") {
  // 10 000 points on a line 0.1 apart: one cluster, 10 000 neighbour queries.
  std::vector<float> xyz;
  for (int i = 0; i < 10000; ++i) xyz.insert(xyz.end(), {0.1f * i, 0.0f, 0.0f});
  uavsim::core::RequestInterrupt();
  CHECK_THROWS_AS(Dbscan(xyz, 3, 0.15, 2), uavsim::core::Interrupted);
  uavsim::core::ClearInterrupt();
  const DbscanClusters all = Dbscan(xyz, 3, 0.15, 2);
  REQUIRE(all.size.size() == 1);
  CHECK(all.size[0] == 10000);
}

}  // namespace uavsim::pipeline
