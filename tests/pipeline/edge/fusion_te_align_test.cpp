// TE-Align (paper Sec. V-A, Eqs. (19)-(20)): the sinusoidal encoding against
// its closed form, window assignment at boundaries, average pooling, empty
// windows and bad input.
#include "pipeline/edge/te_align.h"

#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace uavsim::pipeline {
namespace {

TeAlignConfig Config(int z) {
  TeAlignConfig c;
  c.latent_dim = z;
  return c;
}

LatentFrame Frame(double t_s, std::vector<float> latent) { return {t_s, std::move(latent), {}}; }

}  // namespace

TEST_CASE("TeAlign: encoding equals the closed form of Eq. (19)", "[pipeline]") {
  for (int z : {4, 8, 16, 32, 64}) {
    const TeAlign align(Config(z));
    for (double tau : {0.0, 0.37, 33.3, 199.999, 1234.5}) {
      const std::vector<double> e = align.Encoding(tau);
      REQUIRE(e.size() == static_cast<std::size_t>(z));
      for (int j = 1; j <= z / 2; ++j) {
        const double angle = tau / std::pow(10000.0, 2.0 * j / z);
        CHECK(e[2 * (j - 1)] == Approx(std::sin(angle)).margin(1e-12));
        CHECK(e[2 * (j - 1) + 1] == Approx(std::cos(angle)).margin(1e-12));
      }
    }
  }
}

TEST_CASE("TeAlign: tau is the offset into the window in time units", "[pipeline]") {
  const TeAlign align(Config(16));
  CHECK(align.Tau(0.4, 3) == Approx(0.0).margin(1e-9));
  CHECK(align.Tau(0.433, 3) == Approx(33.0).margin(1e-6));  // milliseconds
  CHECK(align.Tau(1000.1999, 5001) == Approx(199.9).margin(1e-6));
}

TEST_CASE("TeAlign: with the clock origin tau is the frame's time stamp (paper Eq. 19)",
          "[pipeline]") {
  TeAlignConfig config = Config(16);
  config.tau_origin = TauOrigin::kClock;
  const TeAlign align(config);
  CHECK(align.Tau(0.4, 3) == Approx(400.0).margin(1e-9));
  CHECK(align.Tau(0.433, 3) == Approx(433.0).margin(1e-9));
  CHECK(align.Tau(1000.1999, 5001) == Approx(1000199.9).margin(1e-6));
  // Align adds E(t_s / unit) to the latent: two frames of one window, pooled.
  WindowInputs in;
  in.window = 3;
  in.frames[0].push_back({0.41, std::vector<float>(16, 1.0f), {}});
  in.frames[0].push_back({0.47, std::vector<float>(16, -1.0f), {}});
  const AlignedWindow out = align.Align(in);
  for (int j = 1; j <= 8; ++j) {
    const double w = 1.0 / std::pow(10000.0, 2.0 * j / 16);
    CHECK(out.latent[0][2 * (j - 1)] ==
          Approx((std::sin(410.0 * w) + std::sin(470.0 * w)) / 2).margin(1e-6));
    CHECK(out.latent[0][2 * (j - 1) + 1] ==
          Approx((std::cos(410.0 * w) + std::cos(470.0 * w)) / 2).margin(1e-6));
  }
}

TEST_CASE("TeAlign: window k holds (k-1) t^w <= t < k t^w", "[pipeline]") {
  const TeAlign align(Config(16));
  CHECK(align.WindowOf(0.0) == 1);
  CHECK(align.WindowOf(0.199999999) == 1);
  CHECK(align.WindowOf(0.2) == 2);  // a boundary opens the next window
  CHECK(align.WindowOf(0.6) == 4);  // 0.6 / 0.2 = 2.9999999999999996 in binary
  CHECK(align.WindowOf(0.6 - 1e-9) == 3);
  CHECK(align.WindowOf(1.0) == 6);
  CHECK(align.WindowOf(3600.0) == 18001);
  CHECK(align.WindowOf(-0.1) == 0);
  CHECK(align.WindowOf(-0.2) == 0);
  CHECK(align.WindowOf(-0.2000001) == -1);
  CHECK(align.WindowStart_s(4) == Approx(0.6));
  for (int k = 1; k < 2000; ++k) {
    const double start = align.WindowStart_s(k);
    CHECK(align.WindowOf(start) == k);
    CHECK(align.WindowOf(start + 0.2 - 1e-9) == k);
  }
  CHECK_THROWS_AS(align.WindowOf(std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(align.WindowOf(1e10), std::invalid_argument);
}

TEST_CASE("TeAlign: pooling averages latent plus encoding over the window", "[pipeline]") {
  const int z = 4;
  const TeAlign align(Config(z));
  WindowInputs in;
  in.window = 3;  // [0.4, 0.6)
  auto& camera = in.frames[static_cast<int>(Modality::kCamera)];
  camera.push_back(Frame(0.40, {1, 2, 3, 4}));
  camera.push_back(Frame(0.45, {3, 2, 1, 0}));
  camera.push_back(Frame(0.60, {100, 100, 100, 100}));  // next window: ignored
  camera.push_back(Frame(0.38, {100, 100, 100, 100}));  // previous window: ignored
  in.frames[static_cast<int>(Modality::kRadar)].push_back(Frame(0.5999, {-1, 0, 1, 2}));

  const AlignedWindow out = align.Align(in);
  CHECK(out.window == 3);
  CHECK(out.frames_outside_window == 2);
  CHECK(out.mask[0] == 1.0f);
  CHECK(out.mask[1] == 0.0f);
  CHECK(out.mask[2] == 1.0f);

  // Closed form with plain doubles: E(τ) for τ in ms from the window start.
  auto encoding = [&](double tau_ms, int i) {
    const int j = i / 2 + 1;
    const double angle = tau_ms / std::pow(10000.0, 2.0 * j / z);
    return i % 2 == 0 ? std::sin(angle) : std::cos(angle);
  };
  const double a[4] = {1, 2, 3, 4};
  const double b[4] = {3, 2, 1, 0};
  const double r[4] = {-1, 0, 1, 2};
  for (int i = 0; i < z; ++i) {
    const double camera_expected = 0.5 * ((a[i] + encoding(0.0, i)) + (b[i] + encoding(50.0, i)));
    CHECK(out.latent[0][static_cast<std::size_t>(i)] == Approx(camera_expected).margin(1e-6));
    CHECK(out.latent[1][static_cast<std::size_t>(i)] == 0.0f);
    CHECK(out.latent[2][static_cast<std::size_t>(i)] ==
          Approx(r[i] + encoding(199.9, i)).margin(1e-6));
  }
}

TEST_CASE("TeAlign: an empty window gives masks 0 and zero vectors", "[pipeline]") {
  const TeAlign align(Config(8));
  WindowInputs in;
  in.window = 17;
  const AlignedWindow out = align.Align(in);
  for (int m = 0; m < kModalityCount; ++m) {
    CHECK(out.mask[static_cast<std::size_t>(m)] == 0.0f);
    CHECK(out.latent[static_cast<std::size_t>(m)] == std::vector<float>(8, 0.0f));
  }
}

TEST_CASE("TeAlign: bad latents and configurations are refused", "[pipeline]") {
  const TeAlign align(Config(4));
  WindowInputs in;
  in.window = 1;
  in.frames[1].push_back(Frame(0.1, {1, 2, 3}));
  CHECK_THROWS_WITH(align.Align(in), Catch::Contains("3 values, expected z = 4"));
  in.frames[1][0].latent = {1, 2, std::nanf(""), 4};
  CHECK_THROWS_WITH(align.Align(in), Catch::Contains("non-finite"));
  TeAlignConfig odd = Config(5);
  CHECK_THROWS_WITH(TeAlign(odd), Catch::Contains("latent_dim (5)"));
  TeAlignConfig zero_window = Config(4);
  zero_window.window_s = 0.0;
  CHECK_THROWS_WITH(TeAlign(zero_window), Catch::Contains("window_s (0)"));
}

}  // namespace uavsim::pipeline

namespace uavsim::pipeline {
namespace {

// Sec. VI, Fig. 12: the resampling baselines keep one frame's latent as it
// is. Worked by hand: window 1 (0 <= t < 0.2 s) holds camera frames stamped
// 0.15, 0.05, 0.10 s (arrival order) with latents [3 3], [1 1], [2 2]; in
// time order they are [1 1] (first), [2 2] (middle: index floor(3/2) = 1),
// [3 3]. LiDAR: 0.12 and 0.02 s with [5 5], [4 4]: first [4 4], middle
// index floor(2/2) = 1: [5 5]. A frame of window 2 (0.25 s) is ignored.
WindowInputs HandWindow() {
  WindowInputs w;
  w.window = 1;
  w.frames[0] = {Frame(0.15, {3, 3}), Frame(0.05, {1, 1}), Frame(0.10, {2, 2}),
                 Frame(0.25, {9, 9})};
  w.frames[1] = {Frame(0.12, {5, 5}), Frame(0.02, {4, 4})};
  return w;
}

}  // namespace

TEST_CASE("TeAlign resampling: first, middle and random pick the frame worked by hand",
          "[pipeline]") {
  TeAlignConfig c = Config(2);
  c.alignment = Alignment::kFirst;
  AlignedWindow a = TeAlign(c).Align(HandWindow());
  CHECK(a.latent[0] == std::vector<float>{1, 1});
  CHECK(a.latent[1] == std::vector<float>{4, 4});
  CHECK(a.latent[2] == std::vector<float>{0, 0});
  CHECK(a.mask == std::array<float, 3>{1, 1, 0});
  CHECK(a.frames_outside_window == 1);

  c.alignment = Alignment::kMiddle;
  a = TeAlign(c).Align(HandWindow());
  CHECK(a.latent[0] == std::vector<float>{2, 2});
  CHECK(a.latent[1] == std::vector<float>{5, 5});

  // Random: the frame RandomFrameIndex names, in time order, and the same
  // on every call.
  c.alignment = Alignment::kRandom;
  a = TeAlign(c).Align(HandWindow());
  const float camera[3] = {1, 2, 3}, lidar[2] = {4, 5};
  CHECK(a.latent[0][0] == camera[RandomFrameIndex(1, 0, 3)]);
  CHECK(a.latent[1][0] == lidar[RandomFrameIndex(1, 1, 2)]);
  CHECK(TeAlign(c).Align(HandWindow()).latent == a.latent);

  // TE-Align itself on the same window: the mean of latent plus encoding,
  // not any single frame.
  const AlignedWindow te = TeAlign(Config(2)).Align(HandWindow());
  CHECK(te.latent[0][0] != Approx(1.0f));
  CHECK(te.latent[0][0] != Approx(2.0f));
}

TEST_CASE("RandomFrameIndex: in range and spread over the frames", "[pipeline]") {
  // Over 3000 windows of 3 frames each index is drawn about 1000 times: a
  // chi-square of the counts against uniform, 2 degrees of freedom, below
  // its 0.999 quantile 13.8.
  int counts[3] = {0, 0, 0};
  for (std::int64_t k = 1; k <= 3000; ++k) {
    const std::size_t i = RandomFrameIndex(k, 2, 3);
    REQUIRE(i < 3);
    ++counts[i];
  }
  double chi2 = 0.0;
  for (int c : counts) chi2 += (c - 1000.0) * (c - 1000.0) / 1000.0;
  CHECK(chi2 < 13.8);
  CHECK(RandomFrameIndex(7, 0, 1) == 0);
  CHECK_THROWS_AS(RandomFrameIndex(7, 0, 0), std::invalid_argument);
}

}  // namespace uavsim::pipeline
