// Weather reaches every consumer through a sweep: one "/weather" value in the
// spec changes the uplink (rain attenuation of a mmWave carrier, ITU-R
// P.838-3), the LiDAR (attenuation and backscatter change its point count)
// and the radar (rain clutter) of the same point.
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>

#include "core/json_io.h"
#include "core/rain_attenuation.h"
#include "test_support.h"

using uavsim::core::Json;
using uavsim::testing::ReadFile;
using uavsim::testing::RunCli;
using uavsim::testing::TempDir;
using uavsim::testing::WriteFile;

namespace {

// Column `name` of a plain CSV, by row.
std::vector<std::string> Column(const std::string& csv, const std::string& name) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::istringstream h(line);
  for (std::string c; std::getline(h, c, ',');) header.push_back(c);
  const auto at = std::find(header.begin(), header.end(), name) - header.begin();
  REQUIRE(at < static_cast<long>(header.size()));
  std::vector<std::string> out;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::istringstream r(line);
    for (std::string c; std::getline(r, c, ',');) cells.push_back(c);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    out.push_back(at < static_cast<long>(cells.size()) ? cells[at] : "");
  }
  return out;
}

}  // namespace

TEST_CASE("Sweep: rain lowers delivery on a 60 GHz uplink and reaches LiDAR and radar",
          "[sim][sweep][slow]") {
  const std::string dir = TempDir("sweep-weather");
  // Clear-sky Es/N0 22 dB over a 500 m rain-filled path at 60 GHz: rain of
  // R mm/h takes gamma_R(60 GHz, R) * 0.5 km off the SNR.
  WriteFile(dir + "/spec.json", R"({
    "scenario": ")" + std::string(UAVSIM_SOURCE_DIR) +
                                    R"(/scenarios/default.json",
    "set": {"/duration_s": 2, "/pipeline/methods": ["ekf"],
            "/links/default/carrier_ghz": 60, "/links/default/snr_db": 22,
            "/links/default/path_length_m": 500, "/links/default/polarization": "horizontal"},
    "parameters": [{"name": "rain", "pointer": "/weather/rain_mm_h", "values": [0, 20, 60]}]
  })");
  const auto r = RunCli({"sweep", dir + "/spec.json", "--out", dir + "/out", "--quiet"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const std::string summary = ReadFile(dir + "/out/summary.csv");
  const auto camera = Column(summary, "delivery_camera");
  REQUIRE(camera.size() == 3);
  const double d0 = std::stod(camera[0]), d20 = std::stod(camera[1]), d60 = std::stod(camera[2]);
  // Dry: the 22 dB link loses (almost) nothing. 60 mm/h at 60 GHz is
  // ~ 20 dB/km, 10 dB over the path: 16-QAM at 12 dB loses nearly every
  // fragment.
  const double g60 = uavsim::core::RainSpecificAttenuationDbPerKm(
      60.0, 60.0, uavsim::core::Polarization::kHorizontal, 0.0);
  CHECK(g60 * 0.5 > 9.0);
  CHECK(d0 > 0.99);
  CHECK(d20 < d0);
  CHECK(d60 < 0.05);
  // The same rain reached the sensors of those points: the LiDAR's raw
  // point rate and the radar's detections change with it.
  const auto rates = [&](const char* point) {
    const Json m = Json::parse(ReadFile(dir + "/out/points/" + point + "/metrics.json"));
    return m["data_rate_kBps"];
  };
  const Json dry = rates("p0000"), wet = rates("p0002");
  CHECK(dry["lidar"]["raw"].get<double>() != wet["lidar"]["raw"].get<double>());
  CHECK(dry["radar"]["preprocessed"].get<double>() != wet["radar"]["preprocessed"].get<double>());
}
