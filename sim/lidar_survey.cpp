#include "sim/lidar_survey.h"

#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>

#include "core/json_io.h"
#include "core/rng.h"
#include "sensors/lidar_coverage.h"

namespace uavsim::sim {
namespace {

struct Cache {
  std::mutex mutex;
  std::map<std::string, LidarSurvey> surveys;
};

Cache& TheCache() {
  static Cache cache;
  return cache;
}

// FNV-1a of the static world's triangles and materials.
std::uint64_t GeometryHash(const core::WorldGeometry& w) {
  std::uint64_t h = core::HashString("world");
  const auto add = [&h](const void* data, std::size_t bytes) {
    h = core::Mix64(h ^ core::HashString(std::string_view(static_cast<const char*>(data), bytes)));
  };
  for (const core::TriangleMesh& m : w.meshes) {
    add(m.vertices_m.data(), m.vertices_m.size() * sizeof(Eigen::Vector3f));
    add(m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
    add(&m.material, sizeof m.material);
  }
  for (const core::Material& m : w.materials) {
    add(&m.lidar_reflectivity, sizeof m.lidar_reflectivity);
    add(m.name.data(), m.name.size());
  }
  return h;
}

// What the map depends on.
std::string KeyOf(const NodeConfig& node, const Scenario& s, const core::WorldGeometry& world) {
  core::Json key = {{"node", node.id},
                    {"sensor", core::ToJson(node.sensor.lidar)},
                    {"preprocess", core::ToJson(s.pipeline.preprocess.lidar)},
                    {"world", std::to_string(GeometryHash(world))},
                    {"weather", core::ToJson(s.weather)}};
  return key.dump();
}

LidarSurvey Survey(const NodeConfig& node, const Scenario& s, sensors::Lidar& lidar,
                   const pipeline::LidarPreprocessor& preprocessor) {
  const auto& pre = s.pipeline.preprocess.lidar;
  const sensors::LidarCoverage cover =
      sensors::FramesToCover(lidar, pre.voxel_size_m / lidar.max_ray_length_m(),
                             pre.survey_coverage, pre.survey_horizon_s);
  core::RngStream noise(0, "survey/" + node.id);
  auto map = std::make_shared<pipeline::LidarPreprocessor::StaticMap>();
  for (int k = cover.frames; k >= 1; --k)
    preprocessor.AddSurveyScan(lidar.CaptureStatic(-k * lidar.frame_period_s(), s.weather, noise),
                               *map);
  LidarSurvey out;
  out.map = std::move(map);
  out.frames = cover.frames;
  out.coverage = cover.field_cells ? static_cast<double>(cover.covered_cells) /
                                         static_cast<double>(cover.field_cells)
                                   : 1.0;
  return out;
}

}  // namespace

LidarSurvey SurveyStaticScene(const NodeConfig& node, const Scenario& s,
                              const core::WorldGeometry& world, sensors::Lidar& lidar,
                              const pipeline::LidarPreprocessor& preprocessor) {
  const std::string key = KeyOf(node, s, world);
  Cache& cache = TheCache();
  {
    const std::lock_guard<std::mutex> lock(cache.mutex);
    auto it = cache.surveys.find(key);
    if (it != cache.surveys.end()) {
      LidarSurvey hit = it->second;
      hit.from_cache = true;
      return hit;
    }
  }
  // Surveyed outside the lock (nodes are built one after another; two
  // threads surveying the same key make the same map).
  LidarSurvey fresh = Survey(node, s, lidar, preprocessor);
  const std::lock_guard<std::mutex> lock(cache.mutex);
  return cache.surveys.emplace(key, std::move(fresh)).first->second;
}

}  // namespace uavsim::sim
