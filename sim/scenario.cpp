#include "sim/scenario.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "core/machine.h"
#include "core/rng.h"
#include "core/world_geometry.h"

namespace uavsim::sim {

using core::ConfigError;
using core::Json;
using core::Rule;

namespace {

bool IsValidId(const std::string& id) {
  if (id.empty() || id.size() > 64) return false;
  for (char ch : id)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-')) return false;
  return true;
}

// Ids name RNG streams and, later, files: keep them to a safe alphabet.
template <class V>
void CheckId(V& v, const char* key, const std::string& id) {
  const std::string rule = "expected an id of 1 to 64 letters, digits, '_' or '-'";
  if (!v.Has(key))
    v.Check(!id.empty(), key, "missing required key \"" + std::string(key) + "\": " + rule);
  v.Check(IsValidId(id), key, rule + ", got " + core::DescribeValue(Json(id)));
}

std::string Sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

}  // namespace

std::vector<NodeConfig> Scenario::DefaultNodes() {
  // Street intersections of the default 3 x 3 grid city sit at (+-30, +-30).
  NodeConfig cam;
  cam.id = "cam1";
  cam.sensor.type = sensors::SensorType::kFisheyeStereo;
  cam.sensor.fisheye.pose.position_m = {-30.0, -30.0, 1.5};
  cam.sensor.fisheye.pose.rpy_deg = {0.0, -50.0, 45.0};
  NodeConfig lidar;
  lidar.id = "lidar1";
  lidar.sensor.type = sensors::SensorType::kLidar;
  // A Livox Avia-like rosette (the MMAUD data behind the paper used Livox
  // sensors), tilted up at the airspace: a spinning 32-channel LiDAR's 2 deg
  // channel gaps let a 0.2 m-tall drone at 40 m slip between beams.
  lidar.sensor.lidar.preset = sensors::LidarPreset::kLivoxRosette;
  lidar.sensor.lidar.pose.position_m = {30.0, -30.0, 1.5};
  lidar.sensor.lidar.pose.rpy_deg = {0.0, -40.0, 135.0};
  NodeConfig radar;
  radar.id = "radar1";
  radar.sensor.type = sensors::SensorType::kFmcwRadar;
  // Nearer the plaza than the other two: a 0.035 m^2 drone fades into the
  // noise beyond about 50 m for this AWR1843-class link budget.
  radar.sensor.radar.pose.position_m = {-24.0, 24.0, 1.5};
  radar.sensor.radar.pose.rpy_deg = {0.0, -50.0, -45.0};
  return {cam, lidar, radar};
}

// UAV sizes: a few centimetres to an airliner's wing is already generous.
const Rule kUavSize{0.01, 20.0, false, false};

template <class V>
void Visit(V& v, FlightBoxConfig& c) {
  const Rule coordinate = Rule::Range(-1e5, 1e5);
  v("min_m", c.min_m, coordinate);
  v("max_m", c.max_m, coordinate);
  static const char* const kAxis[] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    v.Check(c.min_m[k] < c.max_m[k], "max_m",
            std::string("min_m[") + std::to_string(k) + "] (" + core::FormatNumber(c.min_m[k]) +
                ") must be less than max_m[" + std::to_string(k) + "] (" +
                core::FormatNumber(c.max_m[k]) + "): the box is empty along " + kAxis[k]);
}
UAVSIM_INSTANTIATE_VISIT(FlightBoxConfig);

template <class V>
void Visit(V& v, EpisodeVariationConfig& c) {
  v("sizes_m", c.sizes_m, kUavSize, 0, 64);
  v.Array("regions", c.regions, 0, 64);
}
UAVSIM_INSTANTIATE_VISIT(EpisodeVariationConfig);

template <class V>
void Visit(V& v, UavConfig& c) {
  v("id", c.id);
  CheckId(v, "id", c.id);
  v("role", c.role);
  v.Check(c.role == "target" || c.role == "distractor", "role",
          "expected \"target\" or \"distractor\", got " + core::DescribeValue(Json(c.role)));
  v("size_m", c.size_m, kUavSize);
  v.Object("trajectory", c.trajectory);
  v.Object("episodes", c.episodes);
}
UAVSIM_INSTANTIATE_VISIT(UavConfig);

template <class V>
void Visit(V& v, DistractorsConfig& c) {
  v("birds", c.birds, Rule::Range(0, 1000));
}
UAVSIM_INSTANTIATE_VISIT(DistractorsConfig);

template <class V>
void Visit(V& v, NodeConfig& c) {
  v("id", c.id);
  CheckId(v, "id", c.id);
  v.Object("sensor", c.sensor);
  v("uplink", c.uplink);
}
UAVSIM_INSTANTIATE_VISIT(NodeConfig);

template <class V>
void Visit(V& v, SnrGridConfig& c) {
  v("from", c.from, Rule::Range(-100.0, 100.0));
  v("to", c.to, Rule::Range(-100.0, 100.0));
  v("step", c.step, Rule::Range(0.01, 100.0));
  v.Check(c.from <= c.to, "to", "to must be >= from (" + core::FormatNumber(c.from) + ")");
  v.Check((c.to - c.from) / c.step <= 10000.0, "step",
          "the SNR grid would have more than 10000 points");
}
UAVSIM_INSTANTIATE_VISIT(SnrGridConfig);

template <class V>
void Visit(V& v, OutputsConfig& c) {
  v.Object("snr_db", c.snr_db);
  v("truth_rate_hz", c.truth_rate_hz, Rule::Positive(1000.0));
  v("gospa_c_m", c.gospa_c_m, Rule::Positive(1e6));
}
UAVSIM_INSTANTIATE_VISIT(OutputsConfig);

template <class V>
void Visit(V& v, ExecutionConfig& c) {
  v("static_cache", c.static_cache);
  v("parallel_nodes", c.parallel_nodes);
}
UAVSIM_INSTANTIATE_VISIT(ExecutionConfig);

template <class V>
void Visit(V& v, Scenario& c) {
  v("name", c.name);
  CheckId(v, "name", c.name);
  v("seed", c.seed);
  v("duration_s", c.duration_s, Rule::Positive(86400.0));
  v.Object("world", c.world);
  v.Object("weather", c.weather);
  v.Array("uavs", c.uavs, 1, 64);
  if constexpr (V::kReading) {
    // The default role is the index's: uavs[0] "target", the others "distractor".
    if (const core::Json* raw = v.Raw("uavs"); raw && raw->is_array())
      for (std::size_t i = 1; i < c.uavs.size() && i < raw->size(); ++i)
        if (!(*raw)[i].is_object() || !(*raw)[i].contains("role")) c.uavs[i].role = "distractor";
    v.Check(std::any_of(c.uavs.begin(), c.uavs.end(),
                        [](const UavConfig& u) { return u.role == "target"; }),
            "uavs", "expected at least one UAV with \"role\": \"target\"");
  }
  v.Object("distractors", c.distractors);
  v.Array("nodes", c.nodes, 0, 256);
  v.Map("links", c.links);
  v.Object("base_station", c.base_station);
  v.Object("pipeline", c.pipeline);
  v.Object("outputs", c.outputs);
  v.Object("execution", c.execution);
}
UAVSIM_INSTANTIATE_VISIT(Scenario);

namespace {

// Resident memory of a run beyond its nodes: the world's BVH, LibTorch and
// the model, the libraries (the default run without its nodes' frames is
// about 0.3 GB; NOTES.md).
constexpr double kFixedRunBytes = 0.5e9;

// A node's resident working set per byte of its raw frame: peak RSS growth
// over raw frame size, measured on the default city (NOTES.md: LiDAR 1.05,
// camera 19-21 (MOG2's per-pixel mixtures, rectification maps, the static
// cache), radar 1.7), times a margin of about 1.5.
double WorkingBytesPerRawByte(sensors::SensorType type) {
  switch (type) {
    case sensors::SensorType::kLidar:
      return 1.6;
    case sensors::SensorType::kFisheyeStereo:
      return 32.0;
    case sensors::SensorType::kFmcwRadar:
      return 2.6;
  }
  return 32.0;
}

}  // namespace

ResourceEstimate EstimateResources(const Scenario& s) {
  ResourceEstimate e;
  double max_node_rays_per_s = -1.0;
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const auto& sensor = s.nodes[i].sensor;
    const double rays_per_s = sensor.RaysPerFrame() * sensor.timing().rate_hz;
    e.rays_per_s += rays_per_s;
    if (rays_per_s > max_node_rays_per_s) max_node_rays_per_s = rays_per_s, e.max_rays_node = i;
    if (sensor.RaysPerFrame() > e.max_frame_rays)
      e.max_frame_rays = sensor.RaysPerFrame(), e.max_frame_rays_node = i;
    if (sensor.RawBytesPerFrame() > e.max_frame_bytes)
      e.max_frame_bytes = sensor.RawBytesPerFrame(), e.max_frame_node = i;
    const double node_bytes = WorkingBytesPerRawByte(sensor.type) * sensor.RawBytesPerFrame();
    e.memory_bytes += node_bytes;
    if (node_bytes > e.max_node_memory_bytes)
      e.max_node_memory_bytes = node_bytes, e.max_memory_node = i;
  }
  e.memory_bytes += kFixedRunBytes;
  e.rays_total = e.rays_per_s * s.duration_s;
  return e;
}

namespace {

// A file a scenario refers to, relative to the scenario's folder.
std::filesystem::path RequireFile(const std::string& file, const std::string& pointer,
                                  const std::string& base_dir, const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path p = (fs::path(base_dir) / path).lexically_normal();
  std::error_code ec;
  if (!fs::exists(p, ec)) throw ConfigError(file, pointer, "file not found: " + p.string());
  if (!fs::is_regular_file(p, ec))
    throw ConfigError(file, pointer, "not a regular file: " + p.string());
  return p;
}

// Unique UAV and node ids; every node's uplink names a link.
void CheckIds(const Scenario& s, const std::string& file) {
  std::set<std::string> ids;
  for (std::size_t i = 0; i < s.uavs.size(); ++i)
    if (!ids.insert(s.uavs[i].id).second)
      throw ConfigError(file, "/uavs/" + std::to_string(i) + "/id",
                        "duplicate UAV id \"" + s.uavs[i].id + "\"");
  ids.clear();
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const NodeConfig& n = s.nodes[i];
    const std::string at = "/nodes/" + std::to_string(i);
    if (!ids.insert(n.id).second)
      throw ConfigError(file, at + "/id", "duplicate node id \"" + n.id + "\"");
    if (!s.links.count(n.uplink)) {
      std::string known;
      for (const auto& [name, link] : s.links)
        known += (known.empty() ? "\"" : ", \"") + name + "\"";
      throw ConfigError(file, at + "/uplink",
                        "no link named \"" + n.uplink +
                            "\" in /links (known: " + (known.empty() ? "none" : known) + ")");
    }
  }
}

// The camera pre-processing's stereo search spans disparities up to
// f b / stereo_min_range_m (pipeline/node/camera_preprocessor.h): more than
// the rectified image is wide cannot be searched.
void CheckStereoSearch(const Scenario& s, const std::string& file) {
  const auto& cam = s.pipeline.preprocess.camera;
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const sensors::SensorConfig& sensor = s.nodes[i].sensor;
    if (sensor.type != sensors::SensorType::kFisheyeStereo || cam.raw || s.pipeline.preprocess.raw)
      continue;
    const double f = cam.rectified_focal_px ? *cam.rectified_focal_px
                                            : sensor.fisheye.fx_px / (1.0 + sensor.fisheye.xi);
    const double least_m = f * sensor.fisheye.baseline_m / cam.rectified_width_px;
    if (cam.stereo_min_range_m < least_m)
      throw ConfigError(file, "/pipeline/preprocess/camera/stereo_min_range_m",
                        "expected at least " + core::FormatNumber(least_m) + " m for node \"" +
                            s.nodes[i].id +
                            "\" (nearer, its disparity f b / range would exceed the rectified "
                            "width of " +
                            std::to_string(cam.rectified_width_px) + " px), got " +
                            core::FormatNumber(cam.stereo_min_range_m));
  }
}

// Link names, their outages' nodes, and the files the scenario references
// (the model folder, a city mesh, loaded here so that validate refuses what
// run could not build).
void CheckLinksAndFiles(const Scenario& s, const std::string& file) {
  for (const auto& [name, link] : s.links) {
    if (!IsValidId(name))
      throw ConfigError(file, "/links/" + core::EscapePointerToken(name),
                        "expected a link name of 1 to 64 letters, digits, '_' or '-'");
    std::vector<std::string> users;
    for (const NodeConfig& n : s.nodes)
      if (n.uplink == name) users.push_back(n.id);
    channel::CheckOutageNodes(link, users, file, "/links/" + name);
  }
  if (s.pipeline.model != "default") {
    // A model folder (with its model.json) or the manifest itself.
    namespace fs = std::filesystem;
    const fs::path p = (fs::path(s.base_dir) / s.pipeline.model).lexically_normal();
    std::error_code ec;
    RequireFile(file, "/pipeline/model", s.base_dir,
                fs::is_directory(p, ec) ? (fs::path(s.pipeline.model) / "model.json").string()
                                        : s.pipeline.model);
  }
  if (s.world.city.type == core::CityType::kMesh) {
    namespace fs = std::filesystem;
    const fs::path p = RequireFile(file, "/world/city/path", s.base_dir, s.world.city.path);
    const std::string ext = p.extension().string();
    if (ext != ".obj" && ext != ".OBJ" && ext != ".ply" && ext != ".PLY")
      throw ConfigError(file, "/world/city/path",
                        "expected an .obj or .ply file, got \"" + s.world.city.path + "\"");
    // Loaded and checked here (faces, finite and bounded vertices), so that
    // validate refuses what run could not build; the line names the scenario.
    try {
      core::BuildWorldGeometry(s.world, s.base_dir, core::RngStream(s.seed, "world"));
    } catch (const ConfigError& e) {
      throw ConfigError(file, "/world/city/path", p.string() + ": " + e.message());
    }
  }
}

// The resource guard: rays and bytes per frame, memory, rays per simulated
// second and per run, truth rows.
void CheckResources(const Scenario& s, const std::string& file) {
  const ResourceEstimate e = EstimateResources(s);
  auto node_sensor = [](std::size_t i) { return "/nodes/" + std::to_string(i) + "/sensor"; };
  if (e.max_frame_rays > kMaxRaysPerFrame)
    throw ConfigError(file, node_sensor(e.max_frame_rays_node),
                      "refused: one frame would cast " + Sci(e.max_frame_rays) +
                          " rays; the limit is " + Sci(kMaxRaysPerFrame));
  if (e.max_frame_bytes > kMaxFrameBytes)
    throw ConfigError(file, node_sensor(e.max_frame_node),
                      "refused: one raw frame would take " + Sci(e.max_frame_bytes) +
                          " bytes; the limit is " + Sci(kMaxFrameBytes));
  const double machine_bytes = core::PhysicalMemoryBytes();
  if (machine_bytes > 0.0 && e.memory_bytes > kMaxMemoryShare * machine_bytes)
    throw ConfigError(file, node_sensor(e.max_memory_node),
                      "refused: the run would need about " + Sci(e.memory_bytes) +
                          " bytes of memory (this node " + Sci(e.max_node_memory_bytes) +
                          "); the machine has " + Sci(machine_bytes) + ", of which a run may use " +
                          Sci(kMaxMemoryShare * machine_bytes));
  if (e.rays_per_s > kMaxRaysPerSimSecond)
    throw ConfigError(file, node_sensor(e.max_rays_node),
                      "refused: the sensors would cast " + Sci(e.rays_per_s) +
                          " rays per simulated second (this one " +
                          Sci(s.nodes[e.max_rays_node].sensor.RaysPerFrame() *
                              s.nodes[e.max_rays_node].sensor.timing().rate_hz) +
                          "); the limit is " + Sci(kMaxRaysPerSimSecond));
  if (e.rays_total > kMaxRaysPerRun)
    throw ConfigError(file, "/duration_s",
                      "refused: the run would cast " + Sci(e.rays_total) + " rays (" +
                          Sci(e.rays_per_s) + " per simulated second for " + Sci(s.duration_s) +
                          " s); the limit is " + Sci(kMaxRaysPerRun));
  const double truth_rows = s.outputs.truth_rate_hz * s.duration_s;
  if (truth_rows > kMaxTruthRows)
    throw ConfigError(file, "/outputs/truth_rate_hz",
                      "refused: truth.csv would have " + Sci(truth_rows) + " rows (about " +
                          Sci(truth_rows * 70.0) + " bytes); the limit is " + Sci(kMaxTruthRows) +
                          " rows");
}

// Checks that involve more than one struct.
void CheckScenario(const Scenario& s, const std::string& file) {
  CheckIds(s, file);
  CheckStereoSearch(s, file);
  CheckLinksAndFiles(s, file);
  CheckResources(s, file);
}

}  // namespace

void SetPointer(Json& doc, const std::string& pointer, const Json& value, const std::string& file) {
  if (pointer.empty() || pointer[0] != '/')
    throw ConfigError(file, "", "--set " + pointer + ": expected a JSON pointer starting with /");
  if (!doc.is_object()) throw ConfigError::AboutDocument(file, "is not a JSON object");
  Json* node = &doc;
  std::string at;
  std::size_t pos = 1;
  while (true) {
    const auto slash = pointer.find('/', pos);
    std::string token =
        pointer.substr(pos, slash == std::string::npos ? std::string::npos : slash - pos);
    for (std::size_t i = 0; (i = token.find('~', i)) != std::string::npos; ++i) {
      if (i + 1 < token.size() && (token[i + 1] == '0' || token[i + 1] == '1'))
        token.replace(i, 2, token[i + 1] == '0' ? "~" : "/");
      else
        throw ConfigError(file, pointer, "invalid escape in JSON pointer (~0 or ~1 only)");
    }
    const bool last = slash == std::string::npos;
    at += "/" + core::EscapePointerToken(token);
    if (node->is_array()) {
      std::size_t idx = 0;
      if (token.size() > 1 && token[0] == '0') {
        const auto digit = token.find_first_not_of('0');
        throw ConfigError(file, at,
                          "array index \"" + token +
                              "\" has a leading zero, which RFC 6901 forbids: write " +
                              (digit == std::string::npos ? "0" : token.substr(digit)));
      }
      if (token.empty() || token.find_first_not_of("0123456789") != std::string::npos ||
          token.size() > 6 || (idx = std::stoul(token)) >= node->size())
        throw ConfigError(
            file, at,
            "no such array element (the array has " + std::to_string(node->size()) +
                " elements; the defaults of an array are not addressable, write it in the file)");
      node = &(*node)[idx];
    } else if (node->is_object()) {
      if (last) {
        (*node)[token] = value;
        return;
      }
      if (!node->contains(token)) (*node)[token] = Json::object();
      node = &(*node)[token];
    } else {
      throw ConfigError(file, at, "cannot descend into " + core::DescribeValue(*node));
    }
    if (last) {
      *node = value;
      return;
    }
    pos = slash + 1;
  }
}

void ApplyOverride(Json& doc, const std::string& assignment, const std::string& file) {
  const auto eq = assignment.find('=');
  if (assignment.empty() || assignment[0] != '/' || eq == std::string::npos)
    throw ConfigError(file, "", "--set " + assignment + ": expected /json/pointer=value");
  const std::string text = assignment.substr(eq + 1);
  Json value;
  try {
    value = Json::parse(text);
  } catch (const Json::exception&) {
    value = text;  // a bare word such as orbit
  }
  SetPointer(doc, assignment.substr(0, eq), value, file);
}

Scenario ScenarioFromJson(const Json& doc, const std::string& file, const std::string& base_dir) {
  if (!doc.is_object())
    throw ConfigError::AboutDocument(file, "expected an object, got " + core::DescribeValue(doc));
  Scenario s;
  s.base_dir = base_dir;
  core::FromJson(doc, file, "", s);
  CheckScenario(s, file);
  return s;
}

namespace {

// Whether the override `pointer` sets `target` (itself or an enclosing value).
bool Covers(const std::string& pointer, const std::string& target) {
  return target.compare(0, pointer.size(), pointer) == 0 &&
         (target.size() == pointer.size() || target[pointer.size()] == '/');
}

// Paths given on the command line resolve against the working directory,
// paths written in the file against the file's folder: a relative path that
// an override set is made absolute here, before the scenario's folder is
// joined to it.
void ResolveCommandLinePaths(Json& doc, const std::vector<std::string>& overrides) {
  for (const char* target : {"/pipeline/model", "/world/city/path"}) {
    bool set = false;
    for (const std::string& o : overrides) set = set || Covers(o.substr(0, o.find('=')), target);
    const Json::json_pointer at(target);
    if (!set || !doc.contains(at) || !doc.at(at).is_string()) continue;
    const std::string value = doc.at(at).get<std::string>();
    if (value.empty() || (std::string(target) == "/pipeline/model" && value == "default")) continue;
    if (std::filesystem::path(value).is_relative())
      doc.at(at) = std::filesystem::absolute(value).lexically_normal().string();
  }
  // A TorchScript method's file (/pipeline/methods/i/edge).
  const Json::json_pointer methods("/pipeline/methods");
  if (!doc.contains(methods) || !doc.at(methods).is_array()) return;
  Json& list = doc.at(methods);
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string target = "/pipeline/methods/" + std::to_string(i) + "/edge";
    bool set = false;
    for (const std::string& o : overrides) set = set || Covers(o.substr(0, o.find('=')), target);
    Json& e = list[i];
    if (!set || !e.is_object() || !e.contains("edge") || !e["edge"].is_string()) continue;
    const std::string value = e["edge"].get<std::string>();
    if (!value.empty() && std::filesystem::path(value).is_relative())
      e["edge"] = std::filesystem::absolute(value).lexically_normal().string();
  }
}

}  // namespace

Scenario LoadScenario(const std::string& path, const std::vector<std::string>& overrides) {
  Json doc = core::LoadJsonFile(path);
  for (const auto& o : overrides) ApplyOverride(doc, o, path);
  ResolveCommandLinePaths(doc, overrides);
  const std::string base = std::filesystem::path(path).parent_path().string();
  return ScenarioFromJson(doc, path, base.empty() ? "." : base);
}

Json ResolvedJson(const Scenario& s) { return core::ToJson(s); }

std::vector<std::size_t> TargetIndices(const Scenario& s) {
  std::vector<std::size_t> targets;
  for (std::size_t i = 0; i < s.uavs.size(); ++i)
    if (s.uavs[i].role == "target") targets.push_back(i);
  return targets;
}

std::size_t FirstTarget(const Scenario& s) {
  const auto targets = TargetIndices(s);
  return targets.empty() ? 0 : targets.front();
}

namespace {

// Pre-processing keys added after models were shipped, with their defaults:
// at the default a key is left out of the layout hash, so that models
// trained before it existed still match (they were trained with its default).
const std::vector<std::pair<const char*, core::Json>>& LaterPreprocessKeys() {
  static const std::vector<std::pair<const char*, core::Json>> keys = [] {
    const pipeline::PreprocessConfig d;
    return std::vector<std::pair<const char*, core::Json>>{
        {"/lidar/background", pipeline::LidarBackgroundName(d.lidar.background)},
        {"/lidar/survey_coverage", d.lidar.survey_coverage},
        {"/lidar/survey_horizon_s", d.lidar.survey_horizon_s},
        {"/lidar/weather_echo_rejection", d.lidar.weather_echo_rejection},
        {"/lidar/drone_gate", d.lidar.drone_gate},
        {"/lidar/drone_max_size_m", d.lidar.drone_max_size_m},
        {"/lidar/drone_max_speed_mps", d.lidar.drone_max_speed_mps},
        {"/lidar/drone_count_margin", d.lidar.drone_count_margin},
        {"/lidar/fog_echo_margin", d.lidar.fog_echo_margin},
        {"/lidar/rain_echo_margin", d.lidar.rain_echo_margin},
        {"/radar/selection", pipeline::RadarSelectionName(d.radar.selection)},
        {"/radar/rain_doppler_rejection", d.radar.rain_doppler_rejection},
        {"/radar/rain_doppler_margin_mps", d.radar.rain_doppler_margin_mps},
        {"/radar/persistence_frames", d.radar.persistence_frames},
        {"/radar/min_support", d.radar.min_support},
        {"/radar/gate_m", d.radar.gate_m},
        {"/radar/max_speed_mps", d.radar.max_speed_mps},
        {"/radar/min_peak_snr_db", d.radar.min_peak_snr_db},
        {"/max_observations", d.max_observations},
        {"/weather/source", pipeline::NodeWeatherSourceName(d.weather.source)},
        {"/weather/assumed_rain_mm_h", d.weather.assumed_rain_mm_h},
        {"/weather/assumed_fog_visibility_m", nullptr}};
  }();
  return keys;
}

}  // namespace

std::string LayoutHash(const Scenario& s) {
  const core::Json j = ResolvedJson(s);
  core::Json preprocess = j.at("pipeline").at("preprocess");
  for (const auto& [pointer, value] : LaterPreprocessKeys()) {
    const core::Json::json_pointer p(pointer);
    if (preprocess.contains(p) && preprocess.at(p) == value)
      preprocess.at(p.parent_pointer()).erase(p.back());
  }
  if (preprocess.contains("weather") && preprocess["weather"].empty()) preprocess.erase("weather");
  // Sensor keys added later, likewise: left out at their defaults.
  core::Json nodes = j.at("nodes");
  const double aperture_mm = sensors::LidarConfig{}.receiver_aperture_mm;
  for (core::Json& node : nodes) {
    if (!node.contains("sensor") || !node["sensor"].is_object()) continue;
    core::Json& sensor = node["sensor"];
    if (sensor.contains("receiver_aperture_mm") && sensor["receiver_aperture_mm"] == aperture_mm)
      sensor.erase("receiver_aperture_mm");
  }
  const std::string text = j.at("world").dump() + nodes.dump() + preprocess.dump();
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64
  for (unsigned char ch : text) h = (h ^ ch) * 1099511628211ull;
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace uavsim::sim
