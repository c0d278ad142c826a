// World-frame observations -> IB-CC network inputs, checked by hand.
#include <catch2/catch.hpp>
#include <stdexcept>
#include <vector>

#include "core/json_io.h"
#include "pipeline/node/ib_cc_config.h"
#include "pipeline/node/ib_normalization.h"
#include "test_support.h"

namespace uavsim::pipeline {

TEST_CASE("IbNormalization: positions round-trip through the normalisation", "[pipeline]") {
  IbNormalization n;
  n.centre_m = {10.0, -5.0, 30.0};
  n.scale_m = 4.0;
  const Eigen::Vector3d p(14.0, -5.0, 22.0);
  CHECK(NormalizePosition(p, n).isApprox(Eigen::Vector3d(1.0, 0.0, -2.0)));
  CHECK(DenormalizePosition(NormalizePosition(p, n), n).isApprox(p));
}

TEST_CASE("IbNormalization: points are normalised channel-major", "[pipeline]") {
  IbNormalization n;
  n.centre_m = {1.0, 2.0, 3.0};
  n.scale_m = 2.0;
  n.intensity_scale = 0.5;
  n.velocity_scale_mps = 4.0;
  n.snr_offset_db = 10.0;
  n.snr_scale_db = 5.0;

  PointObservation lidar;
  lidar.channels = 4;
  lidar.values = {3.0f, 2.0f, 1.0f, 0.25f, 1.0f, 4.0f, 3.0f, 0.5f};
  std::vector<float> out(8);
  NormalizePoints(lidar, Modality::kLidar, n, out.data());
  // x of both points, then y, z, intensity.
  CHECK(out == std::vector<float>{1.0f, 0.0f, 0.0f, 1.0f, -1.0f, 0.0f, 0.5f, 1.0f});

  PointObservation radar;
  radar.channels = 5;
  radar.values = {1.0f, 2.0f, 5.0f, -2.0f, 20.0f};
  std::vector<float> r(5);
  NormalizePoints(radar, Modality::kRadar, n, r.data());
  CHECK(r == std::vector<float>{0.0f, 0.0f, 1.0f, -0.5f, 2.0f});

  CHECK_THROWS_WITH(NormalizePoints(radar, Modality::kLidar, n, r.data()),
                    Catch::Contains("expected 4 channels per point, got 5"));
  radar.values.push_back(1.0f);
  CHECK_THROWS_WITH(NormalizePoints(radar, Modality::kRadar, n, r.data()),
                    Catch::Contains("not a whole number"));
  CHECK_THROWS_AS(PointChannels(Modality::kCamera), std::invalid_argument);
}

TEST_CASE("IbNormalization: camera ROI geometry features", "[pipeline]") {
  IbNormalization n;
  n.centre_m = {0.0, 0.0, 10.0};
  n.scale_m = 10.0;
  n.image_width_px = 400.0;
  n.image_height_px = 200.0;
  CameraObservation o;
  o.centre_left_px = {300.0f, 50.0f};
  o.centre_right_px = {200.0f, 100.0f};
  o.side_left_px = 40.0f;
  o.side_right_px = 20.0f;
  o.bearing_left_w = {0.0, 0.6, 0.8};
  o.bearing_right_w = {0.0, 0.0, 1.0};
  o.eye_left_w = {-10.0, 0.0, 10.0};
  o.eye_right_w = {-10.0, 5.0, 0.0};
  const std::vector<float> f = CameraGeometryFeatures(o, n);
  REQUIRE(f.size() == static_cast<std::size_t>(kCameraGeometryFeatures));
  const std::vector<float> expected{0.5f, -0.5f, 0.0f, 0.0f,  0.1f, 0.05f, 0.0f,  0.6f, 0.8f,
                                    0.0f, 0.0f,  1.0f, -1.0f, 0.0f, 0.0f,  -1.0f, 0.5f, -1.0f};
  for (std::size_t i = 0; i < f.size(); ++i) {
    INFO("feature " << i);
    CHECK(f[i] == Approx(expected[i]));
  }
}

TEST_CASE("IbNormalization: fitted to truth positions", "[pipeline]") {
  const std::vector<Eigen::Vector3d> p{{0, 0, 10}, {4, 0, 10}, {0, 2, 10}, {4, 2, 10}};
  const IbNormalization n = FitPositionNormalization(p);
  CHECK(n.centre_m.isApprox(Eigen::Vector3d(2.0, 1.0, 10.0)));
  CHECK(n.scale_m == Approx(2.0));  // largest per-axis standard deviation (x)
  CHECK(FitPositionNormalization({{5, 5, 5}}).scale_m == 1.0);
  CHECK_THROWS_AS(FitPositionNormalization({}), std::invalid_argument);
}

TEST_CASE("IbCcConfig: JSON round trip and strict reading", "[pipeline]") {
  IbCcConfig c;
  c.modality = Modality::kRadar;
  c.latent_dim = 32;
  c.bottleneck = IbBottleneck::kMlp;
  c.normalization.snr_offset_db = -3.0;
  IbCcConfig back;
  core::FromJson(core::ToJson(c), "mem.json", "", back);
  CHECK(back.modality == Modality::kRadar);
  CHECK(back.latent_dim == 32);
  CHECK(back.bottleneck == IbBottleneck::kMlp);
  CHECK(back.normalization.snr_offset_db == -3.0);

  IbCcConfig bad;
  CHECK_THAT(testing::ConfigErrorOf([&] {
               core::FromJson(core::Json::parse(R"({"normalization": {"scale_m": 0}})"), "m.json",
                              "", bad);
             }),
             Catch::Contains("m.json: /normalization/scale_m"));
  CHECK_THAT(testing::ConfigErrorOf([&] {
               core::FromJson(core::Json::parse(R"({"modality": "sonar"})"), "m.json", "", bad);
             }),
             Catch::Contains("/modality") && Catch::Contains("\"camera\", \"lidar\", \"radar\""));
}

}  // namespace uavsim::pipeline
