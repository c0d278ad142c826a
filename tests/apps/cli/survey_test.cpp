// The LiDAR's survey (lidar.background "survey") through the built binary:
// a run surveys once and caches the map on disk; a run that finds the cache
// gives the same outputs byte for byte, so does a run whose cached file was
// damaged (it surveys again and rewrites the same file) and one with the
// disk cache off.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "core/json_io.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::testing::CheckSameRun;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

const std::string kDefault = std::string(UAVSIM_SOURCE_DIR) + "/scenarios/default.json";

// 1 s of the default city with the survey (short: coverage 0.5 over 2 s),
// the disk cache in `cache`.
void Run(const std::string& out, const std::string& cache, std::vector<std::string> extra = {}) {
  ::setenv("UAVSIM_CACHE_DIR", cache.c_str(), 1);
  std::vector<std::string> args = {"run",
                                   kDefault,
                                   "--out",
                                   out,
                                   "--quiet",
                                   "--duration",
                                   "1",
                                   "--set",
                                   "/pipeline/methods=[\"ekf\",\"anchor_track\"]",
                                   "--set",
                                   "/pipeline/preprocess/lidar/survey_coverage=0.5",
                                   "--set",
                                   "/pipeline/preprocess/lidar/survey_horizon_s=2"};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = RunCli(args);
  ::unsetenv("UAVSIM_CACHE_DIR");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
}

std::vector<std::string> CachedFiles(const std::string& cache) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(cache + "/surveys", ec))
    files.push_back(e.path().string());
  return files;
}

}  // namespace

TEST_CASE("Survey: cached on disk, a cached, damaged or uncached survey gives the same run",
          "[sim][slow]") {
  const std::string dir = TempDir("survey");
  const std::string cache = dir + "/cache";
  const std::vector<std::string> survey = {"--set", "/pipeline/preprocess/lidar/background=survey"};
  Run(dir + "/first", cache, survey);
  const auto files = CachedFiles(cache);
  REQUIRE(files.size() == 1);  // one LiDAR node
  const std::string written = ReadFile(files[0]);

  Run(dir + "/cached", cache, survey);
  CheckSameRun(dir + "/first", dir + "/cached");
  CHECK(ReadFile(files[0]) == written);

  std::string damaged = written;
  damaged[damaged.size() / 2] = static_cast<char>(damaged[damaged.size() / 2] ^ 0x40);
  WriteFile(files[0], damaged);
  Run(dir + "/damaged", cache, survey);
  CheckSameRun(dir + "/first", dir + "/damaged");
  CHECK(ReadFile(files[0]) == written);  // surveyed again and rewritten

  Run(dir + "/off", "off", survey);
  CheckSameRun(dir + "/first", dir + "/off");
  CHECK(CachedFiles(cache).size() == 1);

  // The survey differs from the warm-up (the LiDAR sends from its first
  // frame), and the default is the warm-up: an explicit "warmup" changes
  // nothing.
  Run(dir + "/default", cache);
  Run(dir + "/warmup", cache, {"--set", "/pipeline/preprocess/lidar/background=warmup"});
  CheckSameRun(dir + "/default", dir + "/warmup");
  CHECK(ReadFile(dir + "/default/packets.csv") != ReadFile(dir + "/first/packets.csv"));
}

TEST_CASE("Radar score: off at 0 (the default's outputs), listed among the run's node extensions",
          "[sim][slow]") {
  const std::string dir = TempDir("radar_score");
  const std::string cache = dir + "/cache";
  Run(dir + "/default", cache);
  Run(dir + "/zero", cache, {"--set", "/pipeline/preprocess/radar/min_peak_snr_db=0"});
  CheckSameRun(dir + "/default", dir + "/zero");
  Run(dir + "/score", cache, {"--set", "/pipeline/preprocess/radar/min_peak_snr_db=6.4"});
  const auto extensions = [&](const std::string& run) {
    return uavsim::core::Json::parse(ReadFile(run + "/manifest.json"))["node_extensions"]
        .get<std::vector<std::string>>();
  };
  // The default city's nodes: ours where scenarios/default.json switches them on.
  CHECK(extensions(dir + "/default") ==
        std::vector<std::string>{"lidar.weather_echo_rejection=true",
                                 "radar.rain_doppler_rejection=true",
                                 "radar.selection=persistent"});
  CHECK(extensions(dir + "/score") == std::vector<std::string>{"lidar.weather_echo_rejection=true",
                                                               "radar.rain_doppler_rejection=true",
                                                               "radar.min_peak_snr_db=6.4",
                                                               "radar.selection=persistent"});
}

TEST_CASE(
    "Node weather: the truth is listed among a run's oracles; an assumed weather equal to "
    "the truth gives the same run",
    "[sim][slow]") {
  const std::string dir = TempDir("node_weather");
  const std::string cache = dir + "/cache";
  Run(dir + "/truth", cache);
  Run(dir + "/assumed", cache, {"--set", "/pipeline/preprocess/weather/source=assumed"});
  const auto manifest = [&](const std::string& run) {
    return uavsim::core::Json::parse(ReadFile(run + "/manifest.json"));
  };
  CHECK(manifest(dir + "/truth")["oracles"] == uavsim::core::Json::array({"weather=truth"}));
  CHECK(manifest(dir + "/assumed")["oracles"] == uavsim::core::Json::array());
  // The default city is clear, and the assumed weather's default is clear.
  for (const char* f : {"packets.csv", "estimates.csv", "metrics.json"}) {
    INFO(f);
    if (std::string(f) == "metrics.json")
      CHECK(uavsim::testing::WithoutWallClock(
                uavsim::core::Json::parse(ReadFile(dir + "/truth/" + f))) ==
            uavsim::testing::WithoutWallClock(
                uavsim::core::Json::parse(ReadFile(dir + "/assumed/" + f))));
    else
      CHECK(ReadFile(dir + "/truth/" + f) == ReadFile(dir + "/assumed/" + f));
  }
}
