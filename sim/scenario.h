// A scenario: every component's config struct, collected. Loading is strict
// (DESIGN.md): defaults, then the file, then `--set /json/pointer=value`
// overrides; unknown keys, wrong types, out-of-range values, dangling
// references, missing files and absurd resource demands are ConfigErrors
// naming the file and the JSON pointer.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "channel/base_station_config.h"
#include "channel/link_config.h"
#include "core/json_io.h"
#include "core/trajectory.h"
#include "core/weather.h"
#include "core/world.h"
#include "pipeline/pipeline_config.h"
#include "sensors/sensor_config.h"

namespace uavsim::sim {

// A box in the world (ENU, metres), min_m < max_m on every axis.
struct FlightBoxConfig {
  Eigen::Vector3d min_m{-30.0, -30.0, 15.0};
  Eigen::Vector3d max_m{30.0, 30.0, 50.0};
};

// How `uavsim train` varies the target (the first UAV of role "target") from one training episode
// to the next (apps/train/train.h); a run, and any other UAV, ignores it. Empty
// lists change nothing: the target keeps size_m, and its episodes fly
// around the region its own trajectory covers over the scenario's duration,
// widened by 10 m.
struct EpisodeVariationConfig {
  // Each episode's target draws one size (x, y, z in metres, as size_m),
  // uniformly.
  std::vector<Eigen::Vector3d> sizes_m;
  // Episode i flies in regions[(i / 3) % n] (i % 3 picks its trajectory
  // type, so every region gets every type), a box used as the widened
  // region above.
  std::vector<FlightBoxConfig> regions;
};

struct UavConfig {
  std::string id = "target";
  // "target": localized, scored and served; "distractor": flies and is
  // seen, not scored. Unset in the file: uavs[0] is the target, the others
  // distractors (the resolved scenario says so).
  std::string role = "target";
  Eigen::Vector3d size_m{0.5, 0.5, 0.2};
  core::TrajectoryConfig trajectory;
  EpisodeVariationConfig episodes;
};

struct DistractorsConfig {
  int birds = 0;
};

struct NodeConfig {
  std::string id;
  sensors::SensorConfig sensor;
  std::string uplink = "default";
};

struct SnrGridConfig {
  double from = -10.0;
  double to = 30.0;
  double step = 2.0;
};

struct OutputsConfig {
  SnrGridConfig snr_db;
  double truth_rate_hz = 20.0;  // rows per simulated second in truth.csv
  double gospa_c_m = 10.0;      // GOSPA's cut-off with several targets (window_scorer.h)
};

// How the run executes, never what it simulates: every setting gives the
// same outputs, byte for byte (wall times aside). Off is for comparison
// and for finding a fault.
struct ExecutionConfig {
  // Sensors render what is static (the city, from a sensor that never
  // moves) once, and per frame only what moving objects can change.
  bool static_cache = true;
  // Each node makes its next frame on a thread of its own, ahead of its
  // time, while the event loop runs.
  bool parallel_nodes = true;
};

struct Scenario {
  std::string name = "default";
  std::uint64_t seed = 1;
  double duration_s = 60.0;
  core::WorldConfig world;
  core::WeatherConfig weather;
  std::vector<UavConfig> uavs{UavConfig{}};  // roles: UavConfig::role
  DistractorsConfig distractors;
  std::vector<NodeConfig> nodes = DefaultNodes();
  std::map<std::string, channel::LinkConfig> links{{"default", channel::LinkConfig{}}};
  channel::BaseStationConfig base_station;
  pipeline::PipelineConfig pipeline;
  OutputsConfig outputs;
  ExecutionConfig execution;

  // Not part of the file: the folder relative paths are resolved against.
  std::string base_dir = ".";

  // A stereo fisheye camera, a 32-channel LiDAR and a 77 GHz radar at three
  // street corners of the default city, looking up at the default orbit.
  static std::vector<NodeConfig> DefaultNodes();
};

template <class V>
void Visit(V& v, FlightBoxConfig& c);
template <class V>
void Visit(V& v, EpisodeVariationConfig& c);
template <class V>
void Visit(V& v, UavConfig& c);
template <class V>
void Visit(V& v, DistractorsConfig& c);
template <class V>
void Visit(V& v, NodeConfig& c);
template <class V>
void Visit(V& v, SnrGridConfig& c);
template <class V>
void Visit(V& v, OutputsConfig& c);
template <class V>
void Visit(V& v, ExecutionConfig& c);
template <class V>
void Visit(V& v, Scenario& c);

// What a scenario would cost, for the resource guard.
struct ResourceEstimate {
  double rays_per_s = 0.0;              // all sensors, per simulated second
  double rays_total = 0.0;              // over the whole run
  std::size_t max_rays_node = 0;        // the node casting the most rays per second
  double max_frame_rays = 0.0;          // the most rays of any one frame
  std::size_t max_frame_rays_node = 0;  // its node
  double max_frame_bytes = 0.0;         // the largest raw frame of any sensor
  std::size_t max_frame_node = 0;       // its node
  // Resident memory the run would need, bytes: a fixed part (the world, the
  // model, the libraries) plus each node's working set, a multiple of its
  // raw frame measured per sensor type (NOTES.md) with a margin.
  double memory_bytes = 0.0;
  double max_node_memory_bytes = 0.0;  // the node needing the most
  std::size_t max_memory_node = 0;     // its node
};
ResourceEstimate EstimateResources(const Scenario& s);

// Limits of the resource guard.
constexpr double kMaxRaysPerFrame = 1e9;
constexpr double kMaxRaysPerSimSecond = 2e9;
constexpr double kMaxTruthRows = 1e7;
constexpr double kMaxRaysPerRun = 2e12;
constexpr double kMaxFrameBytes = 2.0 * (1ull << 30);
// A run may not need more than this share of the machine's physical memory.
constexpr double kMaxMemoryShare = 0.8;

// Applies one "--set /json/pointer=value" to a document. The value is parsed
// as JSON when it is valid JSON, else taken as a string. Missing objects on
// the way are created; array indices must exist, written without leading
// zeros (RFC 6901). Throws ConfigError "FILE: /pointer: ..." naming `file`,
// the document the override applies to.
void ApplyOverride(core::Json& doc, const std::string& assignment,
                   const std::string& file = "--set");
// The same with the value given as JSON.
void SetPointer(core::Json& doc, const std::string& pointer, const core::Json& value,
                const std::string& file = "--set");

// The UAVs whose role is "target", in scenario order (at least one).
std::vector<std::size_t> TargetIndices(const Scenario& s);
// The first of them: the one the single-target methods localize.
std::size_t FirstTarget(const Scenario& s);

// Loads `path`, applies the overrides, fills the struct and checks every rule
// including cross-references, referenced files and the resource guard.
// Relative paths (/pipeline/model, /world/city/path) resolve against the
// scenario's folder when the file gives them and against the working
// directory when an override does. Throws ConfigError.
Scenario LoadScenario(const std::string& path, const std::vector<std::string>& overrides = {});
// The same from a document already in memory; `file` names it in messages and
// `base_dir` resolves relative paths.
Scenario ScenarioFromJson(const core::Json& doc, const std::string& file,
                          const std::string& base_dir);

// The resolved scenario: every key, defaults filled.
core::Json ResolvedJson(const Scenario& s);

// Fingerprint of what a trained model depends on: the world, the nodes and
// the nodes' pre-processing as resolved (16 hex digits of FNV-1a over their
// JSON).
std::string LayoutHash(const Scenario& s);

}  // namespace uavsim::sim
