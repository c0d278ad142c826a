#include "sim/lidar_survey.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "core/json_io.h"
#include "core/rng.h"
#include "core/sha256.h"
#include "sensors/lidar_coverage.h"
#include "sim/version.h"

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
  core::Json key = {{"build", std::string(Version()) + " " + GitHash()},
                    {"node", node.id},
                    {"sensor", core::ToJson(node.sensor.lidar)},
                    {"preprocess", core::ToJson(s.pipeline.preprocess.lidar)},
                    {"known_weather", core::ToJson(s.pipeline.preprocess.weather.Known(s.weather))},
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

constexpr char kMagic[8] = {'U', 'A', 'V', 'S', 'U', 'R', 'V', '1'};
constexpr std::size_t kDigestBytes = 32;

template <class T>
void Put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// Reads a T at `at` if the bytes hold one before `end`.
template <class T>
bool Take(const std::string& in, std::size_t& at, std::size_t end, T& v) {
  if (end - at < sizeof v) return false;
  std::memcpy(&v, in.data() + at, sizeof v);
  at += sizeof v;
  return true;
}

std::string DigestBytes(const std::string& bytes) {
  const std::string hex = core::Sha256Hex(bytes);
  std::string raw(kDigestBytes, '\0');
  for (std::size_t i = 0; i < kDigestBytes; ++i)
    raw[i] = static_cast<char>(std::stoi(hex.substr(2 * i, 2), nullptr, 16));
  return raw;
}

std::string FileFor(const std::string& dir, const std::string& key) {
  return (std::filesystem::path(dir) / "surveys" / (core::Sha256Hex(key) + ".survey")).string();
}

std::optional<LidarSurvey> ReadCached(const std::string& dir, const std::string& key) {
  if (dir.empty()) return std::nullopt;
  std::error_code ec;
  const std::string path = FileFor(dir, key);
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  try {
    return DecodeSurvey(core::ReadFileBytes(path), key);
  } catch (const std::exception&) {
    return std::nullopt;  // unreadable: survey again
  }
}

// Best effort: a cache that cannot be written costs the next run a survey.
void WriteCached(const std::string& dir, const std::string& key, const LidarSurvey& survey) {
  if (dir.empty()) return;
  try {
    const std::string path = FileFor(dir, key);
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    core::WriteFileAtomic(path, EncodeSurvey(key, survey));
  } catch (const std::exception&) {
  }
}

}  // namespace

std::string SurveyCacheDir() {
  const auto env = [](const char* name) -> std::string {
    const char* v = std::getenv(name);
    return v ? v : "";
  };
  const std::string own = env("UAVSIM_CACHE_DIR");
  if (own == "off") return "";
  if (!own.empty()) return own;
  const std::string xdg = env("XDG_CACHE_HOME");
  if (!xdg.empty()) return (std::filesystem::path(xdg) / "uavsim").string();
  const std::string home = env("HOME");
  if (!home.empty()) return (std::filesystem::path(home) / ".cache" / "uavsim").string();
  return "";
}

std::string EncodeSurvey(const std::string& key, const LidarSurvey& survey) {
  std::vector<std::uint64_t> voxels(survey.map->begin(), survey.map->end());
  std::sort(voxels.begin(), voxels.end());
  std::string out(kMagic, sizeof kMagic);
  Put<std::uint64_t>(out, key.size());
  out += key;
  Put<std::int32_t>(out, survey.frames);
  Put<double>(out, survey.coverage);
  Put<std::uint64_t>(out, voxels.size());
  out.append(reinterpret_cast<const char*>(voxels.data()), voxels.size() * sizeof(std::uint64_t));
  out += DigestBytes(out);
  return out;
}

std::optional<LidarSurvey> DecodeSurvey(const std::string& bytes, const std::string& key) {
  if (bytes.size() < sizeof kMagic + kDigestBytes) return std::nullopt;
  const std::size_t end = bytes.size() - kDigestBytes;
  if (std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) return std::nullopt;
  if (DigestBytes(bytes.substr(0, end)) != bytes.substr(end)) return std::nullopt;
  std::size_t at = sizeof kMagic;
  std::uint64_t key_size = 0, count = 0;
  LidarSurvey s;
  if (!Take(bytes, at, end, key_size) || key_size != key.size() || end - at < key_size ||
      bytes.compare(at, key_size, key) != 0)
    return std::nullopt;
  at += key_size;
  std::int32_t frames = 0;
  if (!Take(bytes, at, end, frames) || !Take(bytes, at, end, s.coverage) ||
      !Take(bytes, at, end, count) || count != (end - at) / sizeof(std::uint64_t) ||
      (end - at) % sizeof(std::uint64_t) != 0)
    return std::nullopt;
  s.frames = frames;
  auto map = std::make_shared<pipeline::LidarPreprocessor::StaticMap>();
  map->reserve(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    std::uint64_t v = 0;
    Take(bytes, at, end, v);
    map->insert(v);
  }
  s.map = std::move(map);
  return s;
}

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
  // Read or surveyed outside the lock (nodes are built one after another;
  // two threads surveying the same key make the same map).
  const std::string dir = SurveyCacheDir();
  std::optional<LidarSurvey> cached = ReadCached(dir, key);
  LidarSurvey fresh;
  if (cached) {
    fresh = std::move(*cached);
    fresh.from_cache = true;
  } else {
    fresh = Survey(node, s, lidar, preprocessor);
    WriteCached(dir, key, fresh);
  }
  const std::lock_guard<std::mutex> lock(cache.mutex);
  return cache.surveys.emplace(key, std::move(fresh)).first->second;
}

}  // namespace uavsim::sim
