// PreprocessConfig's JSON mapping: defaults round-trip, strict errors.
#include <catch2/catch.hpp>
#include <string>

#include "core/error.h"
#include "core/json_io.h"
#include "pipeline/node/preprocess_config.h"

namespace uavsim::pipeline {
namespace {

std::string ErrorOf(const char* json) {
  try {
    PreprocessConfig c;
    core::FromJson(core::ParseJsonText(json, "s.json"), "s.json", "/pipeline/preprocess", c);
  } catch (const core::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST_CASE("PreprocessConfig: defaults round-trip through JSON", "[pipeline]") {
  const core::Json j = core::ToJson(PreprocessConfig{});
  CHECK(j["raw"] == false);
  CHECK(j["camera"]["rectified_focal_px"].is_null());  // null: fx_px / (1 + xi)
  CHECK(j["lidar"]["voxel_size_m"] == 0.5);
  CHECK(j["radar"]["clusters_kept"] == 1);
  PreprocessConfig back;
  core::FromJson(j, "s.json", "/pipeline/preprocess", back);
  CHECK(core::ToJson(back) == j);

  PreprocessConfig c;
  core::FromJson(core::ParseJsonText(R"({"camera": {"raw": true, "rectified_focal_px": 200},
                                         "lidar": {"warmup_frames": 5}})",
                                     "s.json"),
                 "s.json", "/pipeline/preprocess", c);
  CHECK(c.CameraRaw());
  CHECK_FALSE(c.LidarRaw());
  CHECK(*c.camera.rectified_focal_px == 200.0);
  CHECK(c.lidar.warmup_frames == 5);
}

TEST_CASE("PreprocessConfig: bad values name the pointer and the rule", "[pipeline]") {
  CHECK_THAT(ErrorOf(R"({"lidar": {"occupancy_threshold": 0}})"),
             Catch::Contains("s.json: /pipeline/preprocess/lidar/occupancy_threshold") &&
                 Catch::Contains("got 0"));
  CHECK_THAT(ErrorOf(R"({"radar": {"cluster_eps_m": -1}})"),
             Catch::Contains("/pipeline/preprocess/radar/cluster_eps_m"));
  CHECK_THAT(ErrorOf(R"({"camera": {"min_blob_area": 3}})"),
             Catch::Contains("/pipeline/preprocess/camera") &&
                 Catch::Contains("did you mean \"min_blob_area_px\""));
  CHECK_THAT(ErrorOf(R"({"camera": {"roi_margin": 0.5}})"),
             Catch::Contains("/pipeline/preprocess/camera/roi_margin"));
}

}  // namespace
}  // namespace uavsim::pipeline

namespace uavsim::pipeline {
namespace {

TEST_CASE("NodeWeatherConfig: the truth, or the assumed weather whatever falls; oracles listed",
          "[pipeline]") {
  core::WeatherConfig truth;
  truth.rain_mm_h = 10.0;
  truth.fog_visibility_m = 300.0;
  truth.illumination = 0.5;
  NodeWeatherConfig c;
  CHECK(core::ToJson(c.Known(truth)) == core::ToJson(truth));
  c.source = NodeWeatherSource::kAssumed;
  core::WeatherConfig known = c.Known(truth);
  CHECK(known.rain_mm_h == 0.0);
  CHECK_FALSE(known.fog_visibility_m.has_value());
  c.assumed_rain_mm_h = 2.0;
  c.assumed_fog_visibility_m = 1000.0;
  known = c.Known(truth);
  CHECK(known.rain_mm_h == 2.0);
  CHECK(known.fog_visibility_m == 1000.0);

  PreprocessConfig p;  // no weather consumer on: nothing is handed the truth
  CHECK(NodeOracles(p).empty());
  p.lidar.weather_echo_rejection = true;
  CHECK(NodeOracles(p) == std::vector<std::string>{"weather=truth"});
  p.lidar.raw = true;
  CHECK(NodeOracles(p).empty());
  p.radar.rain_doppler_rejection = true;
  CHECK(NodeOracles(p) == std::vector<std::string>{"weather=truth"});
  p.weather.source = NodeWeatherSource::kAssumed;
  CHECK(NodeOracles(p).empty());
  CHECK_THAT(ErrorOf(R"({"weather": {"source": "meter"}})"),
             Catch::Contains("/pipeline/preprocess/weather/source"));
  CHECK_THAT(ErrorOf(R"({"weather": {"assumed_fog_visibility_m": 0}})"),
             Catch::Contains("/pipeline/preprocess/weather/assumed_fog_visibility_m"));
}

}  // namespace
}  // namespace uavsim::pipeline
