#include "sim/run_map.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/physical_constants.h"
#include "sensors/fisheye_model.h"
#include "sensors/raycast_scene.h"

namespace uavsim::sim {
namespace {

using results::FormatFixed;

// The target's path sampled every 0.25 s (its closed form: no simulation).
std::vector<Eigen::Vector3d> TargetPath(const Scenario& s, const WorldModel& world) {
  std::vector<Eigen::Vector3d> path;
  const int steps = std::max(1, static_cast<int>(std::ceil(s.duration_s / 0.25)));
  for (int i = 0; i <= steps; ++i)
    path.push_back(world.target().StateAt(std::min(s.duration_s, 0.25 * i)).position_m);
  return path;
}

// The square (centre, half side) holding the nodes, the base station and the
// target's path, with a margin of 60 % or 30 m, whichever is larger (enough
// of the city around them to see where they are).
struct Region {
  Eigen::Vector2d centre;
  double half_m = 0.0;
};

Region AreaOfInterest(const Scenario& s, const WorldModel& world) {
  Eigen::Vector2d lo = s.base_station.position_m.head<2>(), hi = lo;
  const auto add = [&](const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  };
  for (const NodeConfig& n : s.nodes) add(n.sensor.pose().position_m);
  for (const Eigen::Vector3d& p : TargetPath(s, world)) add(p);
  const double half = 0.5 * (hi - lo).maxCoeff();
  return {0.5 * (lo + hi), half + std::max(30.0, 0.6 * half)};
}

double CellSize(double side_m) {
  for (double c : {0.5, 1.0, 2.0, 4.0, 5.0, 10.0, 20.0, 50.0, 100.0})
    if (side_m / c <= 200.0) return c;
  return std::ceil(side_m / 200.0);
}

// Half the field of view across the image or scan, radians (pi: all round).
double HalfFieldOfView(const sensors::SensorConfig& c) {
  switch (c.type) {
    case sensors::SensorType::kLidar:
      return c.lidar.preset == sensors::LidarPreset::kLivoxRosette
                 ? 0.5 * c.lidar.fov_deg * core::kPi / 180
                 : core::kPi;
    case sensors::SensorType::kFmcwRadar:
      return 0.5 * c.radar.fov_azimuth_deg * core::kPi / 180.0;
    default: {
      // The widest ray along the image's middle row (optical axis +z).
      const sensors::FisheyeModel model(c.fisheye);
      double widest = 0.0;
      const double v = c.fisheye.cy_px;
      for (double u : {0.0, static_cast<double>(c.fisheye.width_px - 1)}) {
        const Eigen::Vector3d ray = model.Unproject(u, v);
        if (ray.squaredNorm() > 0)
          widest = std::max(widest, std::acos(std::clamp(ray.z(), -1.0, 1.0)));
      }
      return std::min(widest, core::kPi);
    }
  }
}

// How far the sensor sees (metres; infinite for the camera).
double SensorRange(const sensors::SensorConfig& c) {
  switch (c.type) {
    case sensors::SensorType::kLidar:
      return c.lidar.max_range_m;
    case sensors::SensorType::kFmcwRadar: {
      // The beat frequency's Nyquist limit, as sensors/fmcw_radar.cpp.
      const double slope_hz_per_s =
          c.radar.bandwidth_mhz * 1e6 / (c.radar.chirp_duration_us * 1e-6);
      return c.radar.sample_rate_msps * 1e6 * core::kSpeedOfLight_mps / (2.0 * slope_hz_per_s);
    }
    default:
      return INFINITY;
  }
}

}  // namespace

results::CsvTable WorldTopTable(const Scenario& s, const WorldModel& world) {
  const Region region = AreaOfInterest(s, world);
  const double cell = CellSize(2.0 * region.half_m);
  const int n = static_cast<int>(std::ceil(2.0 * region.half_m / cell));
  const Eigen::Vector2d origin = region.centre - Eigen::Vector2d::Constant(0.5 * n * cell);
  const sensors::RaycastScene& scene = world.scene();
  const float top = static_cast<float>(scene.static_bounds().max().z() + 1.0);
  results::CsvTable table({"x_m", "y_m", "height_m", "surface"});
  std::vector<sensors::Ray> rays(static_cast<std::size_t>(n));
  std::vector<sensors::RayHit> hits(rays.size());
  for (int j = 0; j < n; ++j) {
    const double y = origin.y() + (j + 0.5) * cell;
    for (int i = 0; i < n; ++i) {
      sensors::Ray& r = rays[static_cast<std::size_t>(i)];
      r.origin_m = Eigen::Vector3f(static_cast<float>(origin.x() + (i + 0.5) * cell),
                                   static_cast<float>(y), top);
      r.direction = -Eigen::Vector3f::UnitZ();
    }
    scene.IntersectManyStatic(rays.data(), hits.data(), rays.size());
    for (int i = 0; i < n; ++i) {
      const sensors::RayHit& h = hits[static_cast<std::size_t>(i)];
      if (!h.hit()) continue;
      const double height = top - h.t;
      if (h.material == core::kMaterialGround && height <= 0.25) continue;
      table.AddRow({FormatFixed(rays[static_cast<std::size_t>(i)].origin_m.x(), 3),
                    FormatFixed(y, 3), FormatFixed(height, 2), scene.material(h.material).name});
    }
  }
  return table;
}

results::CsvTable LayoutTable(const Scenario& s, const WorldModel& world) {
  results::CsvTable table({"object", "kind", "x_m", "y_m", "z_m"});
  const auto row = [&](const std::string& object, const std::string& kind,
                       const Eigen::Vector3d& p) {
    table.AddRow(
        {object, kind, FormatFixed(p.x(), 3), FormatFixed(p.y(), 3), FormatFixed(p.z(), 3)});
  };
  for (const NodeConfig& n : s.nodes) row(n.id, n.sensor.modality(), n.sensor.pose().position_m);
  row("base_station", "base_station", s.base_station.position_m);
  const std::vector<Eigen::Vector3d> path = TargetPath(s, world);
  for (const NodeConfig& n : s.nodes) {
    const Eigen::Isometry3d X_WS = n.sensor.pose().ToIsometry();
    const Eigen::Vector3d p = X_WS.translation();
    double reach = 0.0;
    for (const Eigen::Vector3d& q : path) reach = std::max(reach, (q - p).head<2>().norm());
    const double radius = std::min(1.15 * reach, SensorRange(n.sensor));
    // Boresight: body x (REP 103) for every sensor; the camera's optical z
    // is the body's x.
    const Eigen::Vector3d forward = X_WS.linear().col(0);
    const double azimuth = std::atan2(forward.y(), forward.x());
    const double half = HalfFieldOfView(n.sensor);
    const bool full = half >= core::kPi - 1e-9;
    const int arc_points = 48;
    if (!full) row(n.id, "fov", p);
    for (int k = 0; k <= arc_points; ++k) {
      const double a =
          full ? 2 * core::kPi * k / arc_points : azimuth - half + 2 * half * k / arc_points;
      row(n.id, "fov", p + radius * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
    }
    if (!full) row(n.id, "fov", p);
  }
  return table;
}

}  // namespace uavsim::sim
