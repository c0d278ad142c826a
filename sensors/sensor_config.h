// One sensing node's sensor: a tagged union over the sensor types. The JSON
// is flat: {"type": "lidar", "rate_hz": 10, "pose": {...}, ...}.
#pragma once

#include <cstdint>
#include <string>

#include "sensors/fisheye_stereo_config.h"
#include "sensors/fmcw_radar_config.h"
#include "sensors/lidar_config.h"

namespace uavsim::sensors {

enum class SensorType { kFisheyeStereo, kLidar, kFmcwRadar };

struct SensorConfig {
  SensorType type = SensorType::kFisheyeStereo;
  FisheyeStereoConfig fisheye;
  LidarConfig lidar;
  FmcwRadarConfig radar;

  const FrameTiming& timing() const;
  const core::PoseConfig& pose() const;
  // The modality name used in outputs: "camera", "lidar" or "radar".
  const char* modality() const;
  // Cost estimates for the resource guard and the data-rate table.
  double RaysPerFrame() const;
  double RawBytesPerFrame() const;

  // Calls f with the active type's config.
  template <class F>
  decltype(auto) WithActive(F&& f) const {
    switch (type) {
      case SensorType::kLidar:
        return f(lidar);
      case SensorType::kFmcwRadar:
        return f(radar);
      default:
        return f(fisheye);
    }
  }
};

template <class V>
void Visit(V& v, SensorConfig& c);

}  // namespace uavsim::sensors
