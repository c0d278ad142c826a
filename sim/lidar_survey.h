// A LiDAR node's survey of its static surroundings (lidar.background
// "survey"; paper Sec. IV-A: "the point cloud representing the static
// surroundings can be obtained by performing multiple prior measurements").
//
// Before the run's first frame the node scans the static world alone (no
// UAV, bird or distractor: Lidar::CaptureStatic) in the run's weather, for
// sensors::FramesToCover(lidar, voxel_size_m / reach, survey_coverage,
// survey_horizon_s) frames ending at t = 0 (reach: the range at which the
// sensor detects a white target head-on), so that every voxel-sized patch
// of surface within reach is, to the stated coverage, hit at least once
// whatever its distance. Every voxel a survey scan returns from is static
// (LidarPreprocessor::AddSurveyScan).
//
// Determinism: the survey's noise comes from the stream "survey/<node id>"
// under seed 0, not the run's seed: a site is surveyed once, and every
// flight over it (every seed) uses the same map.
//
// Cache: a survey is keyed by the node's sensor, its LiDAR pre-processing,
// a hash of the world's static geometry, the weather and this build
// (version and git hash). It is kept for the process's life and written to
// SurveyCacheDir() as surveys/<SHA-256 of the key>.survey (atomically), so
// later runs, a sweep's points and a collection's episodes on this machine
// pay nothing for it. A cached file is used only if it is whole: its magic,
// its own copy of the key (equal to the wanted one) and the SHA-256 of its
// bytes are checked; anything else is surveyed again and rewritten. The map
// is the same either way (a pure function of the key), so outputs are too.
// Thread-safe.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "core/world_geometry.h"
#include "pipeline/node/lidar_preprocessor.h"
#include "sensors/lidar.h"
#include "sim/scenario.h"

namespace uavsim::sim {

struct LidarSurvey {
  std::shared_ptr<const pipeline::LidarPreprocessor::StaticMap> map;
  int frames = 0;           // scans the survey made
  double coverage = 0.0;    // share of the field's cells they hit
  bool from_cache = false;  // an earlier survey of this process was reused
};

// The survey of `node` (a LiDAR node whose lidar.background is "survey")
// with `lidar` (the node's sensor on a scene view of its own; the survey
// casts into it and leaves it unposed) and the node's pre-processor.
// Where surveys are cached on disk: $UAVSIM_CACHE_DIR, else
// $XDG_CACHE_HOME/uavsim, else $HOME/.cache/uavsim; "" (no disk cache) when
// UAVSIM_CACHE_DIR is "off" or no folder is known.
std::string SurveyCacheDir();

// A survey file's bytes for `key` (the map's voxels sorted), and back: the
// survey if `bytes` are a whole survey file written for exactly `key`,
// else nothing.
std::string EncodeSurvey(const std::string& key, const LidarSurvey& survey);
std::optional<LidarSurvey> DecodeSurvey(const std::string& bytes, const std::string& key);

LidarSurvey SurveyStaticScene(const NodeConfig& node, const Scenario& s,
                              const core::WorldGeometry& world, sensors::Lidar& lidar,
                              const pipeline::LidarPreprocessor& preprocessor);

}  // namespace uavsim::sim
