// The run's map files (sim/run_map.h) against closed forms: a box city's
// roofs seen from above, and the fields of view of sensors whose extent
// follows from their configs.
#include "sim/run_map.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/json_io.h"
#include "results/csv.h"
#include "sim/scenario.h"
#include "sim/world_model.h"
#include "test_support.h"

using uavsim::core::Json;
using uavsim::sim::LayoutTable;
using uavsim::sim::Scenario;
using uavsim::sim::ScenarioFromJson;
using uavsim::sim::WorldModel;
using uavsim::sim::WorldTopTable;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<std::vector<std::string>> Rows(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line)) rows.push_back(uavsim::results::SplitCsvLine(line));
  return rows;
}

// An open field with one OBJ box, 10 m x 6 m x 20 m, spanning x in [10, 20],
// y in [-3, 3]; a target that moves 1 mm from (0, 0, 30); nodes as given.
Scenario BoxWorld(const std::string& nodes_json) {
  const std::string dir = uavsim::testing::TempDir("runmap");
  std::string obj;
  for (int i = 0; i < 8; ++i)
    obj += "v " + std::to_string(i & 1 ? 20 : 10) + " " + std::to_string(i & 2 ? 3 : -3) + " " +
           std::to_string(i & 4 ? 20 : 0) + "\n";
  // Twelve triangles of the box (winding does not matter to a ray from above).
  obj +=
      "f 1 2 4\nf 1 4 3\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 4 8\nf 3 8 7\n"
      "f 1 3 7\nf 1 7 5\nf 2 4 8\nf 2 8 6\n";
  uavsim::testing::WriteFile(dir + "/box.obj", obj);
  const Json doc = Json::parse(R"({"duration_s": 2,
    "world": {"city": {"type": "mesh", "path": "box.obj"}},
    "uavs": [{"id": "target", "trajectory": {"type": "waypoints",
      "points_m": [[0, 0, 30], [0.001, 0, 30]]}}],
    "base_station": {"position_m": [0, 0, 10]},
    "nodes": )" + nodes_json + "}");
  return ScenarioFromJson(doc, dir + "/s.json", dir);
}

}  // namespace

TEST_CASE("world_top.csv: a box's roof at its height inside its footprint, nothing outside",
          "[sim]") {
  const Scenario s = BoxWorld(R"([{"id": "r", "sensor": {"type": "fmcw_radar",
      "pose": {"position_m": [-20, 0, 1.5], "rpy_deg": [0, 0, 0]}}}])");
  const WorldModel world(s);
  const auto rows = Rows(WorldTopTable(s, world).str());
  REQUIRE(!rows.empty());
  std::size_t inside = 0;
  for (const auto& r : rows) {
    const double x = std::stod(r[0]), y = std::stod(r[1]), h = std::stod(r[2]);
    INFO(x << " " << y);
    // Every listed cell's centre lies on the box (cells straddling its
    // edge may see the roof or the ground: then they are left out).
    CHECK(x >= 10.0 - 1.0);
    CHECK(x <= 20.0 + 1.0);
    CHECK(std::abs(y) <= 3.0 + 1.0);
    CHECK(h == Approx(20.0).margin(0.01));
    if (x > 10.5 && x < 19.5 && std::abs(y) < 2.5) ++inside;
  }
  // The area of interest spans x in [-20, 0] plus margins (30 m): a 0.5 m
  // grid. The box's interior, 9 m x 5 m, holds about 18 x 10 cells.
  CHECK(inside >= 150);
  CHECK(inside <= 200);
}

TEST_CASE("layout.csv: nodes, base station and fields of view from the sensors' configs", "[sim]") {
  // A radar looking along +y (yaw 90), level: its wedge spans azimuths 90 +-
  // 60 degrees out to R_max = f_s c / (2 B / T_c) (10 MS/s, 900 MHz in 60
  // us: 99.93 m), or 1.15 x the farthest the target comes if nearer. A level
  // camera (yaw 0): Mei with xi = 1 lifts m = tan(theta / 2), so the image's
  // left border (u = 0, 320 px from cx at fx = 230) is theta = 2 atan(320 /
  // 230). A spinning LiDAR: a full circle.
  const Scenario s = BoxWorld(R"([
    {"id": "rad", "sensor": {"type": "fmcw_radar", "fov_azimuth_deg": 120,
       "pose": {"position_m": [0, -150, 1.5], "rpy_deg": [0, 0, 90]}}},
    {"id": "cam", "sensor": {"type": "fisheye_stereo", "xi": 1.0, "fx_px": 230, "fy_px": 230,
       "cx_px": 320, "cy_px": 240, "width_px": 640, "height_px": 480,
       "pose": {"position_m": [-10, 0, 1.5], "rpy_deg": [0, 0, 0]}}},
    {"id": "lid", "sensor": {"type": "lidar", "preset": "spinning32", "max_range_m": 200,
       "pose": {"position_m": [5, 5, 1.5], "rpy_deg": [0, 0, 0]}}}])");
  const WorldModel world(s);
  const auto rows = Rows(LayoutTable(s, world).str());
  std::vector<std::vector<std::string>> fov_rad, fov_cam, fov_lid;
  std::vector<std::string> points;
  for (const auto& r : rows) {
    if (r[1] != "fov") points.push_back(r[0] + "," + r[1] + "," + r[2] + "," + r[3]);
    if (r[1] == "fov" && r[0] == "rad") fov_rad.push_back(r);
    if (r[1] == "fov" && r[0] == "cam") fov_cam.push_back(r);
    if (r[1] == "fov" && r[0] == "lid") fov_lid.push_back(r);
  }
  CHECK(points == std::vector<std::string>{"rad,radar,0.000,-150.000", "cam,camera,-10.000,0.000",
                                           "lid,lidar,5.000,5.000",
                                           "base_station,base_station,0.000,0.000"});
  const auto polar = [](const std::vector<std::string>& r, double x0, double y0) {
    const double dx = std::stod(r[2]) - x0, dy = std::stod(r[3]) - y0;
    return std::make_pair(std::hypot(dx, dy), std::atan2(dy, dx) * 180.0 / kPi);
  };
  // Radar: the node, the arc, the node again; the target is 150 m away, so
  // the radius is R_max.
  REQUIRE(fov_rad.size() >= 4);
  CHECK(polar(fov_rad.front(), 0, -150).first == Approx(0.0).margin(1e-3));
  CHECK(polar(fov_rad.back(), 0, -150).first == Approx(0.0).margin(1e-3));
  const double r_max = 10e6 * 299792458.0 / (2.0 * 900e6 / 60e-6);
  CHECK(polar(fov_rad[1], 0, -150).first == Approx(r_max).margin(3e-3));
  CHECK(polar(fov_rad[1], 0, -150).second == Approx(30.0).margin(1e-3));
  CHECK(polar(fov_rad[fov_rad.size() - 2], 0, -150).second == Approx(150.0).margin(1e-3));
  // Camera: the target hovers 10 m away horizontally: radius 11.5 m.
  const double theta = 2.0 * std::atan(320.0 / 230.0) * 180.0 / kPi;
  CHECK(polar(fov_cam[1], -10, 0).first == Approx(11.5).margin(3e-3));
  CHECK(polar(fov_cam[1], -10, 0).second == Approx(-theta).margin(0.05));
  CHECK(polar(fov_cam[fov_cam.size() - 2], -10, 0).second == Approx(theta).margin(0.05));
  // LiDAR: a closed circle around the node, radius 1.15 x |(0,0) - (5,5)|.
  REQUIRE(fov_lid.size() >= 8);
  CHECK(fov_lid.front() == std::vector<std::string>{"lid", "fov", fov_lid.back()[2],
                                                    fov_lid.back()[3], fov_lid.back()[4]});
  for (const auto& r : fov_lid)
    CHECK(polar(r, 5, 5).first == Approx(1.15 * std::sqrt(50.0)).margin(3e-3));
}
