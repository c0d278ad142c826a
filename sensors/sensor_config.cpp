#include "sensors/sensor_config.h"

#include "core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

const FrameTiming& SensorConfig::timing() const {
  return WithActive([](const auto& c) -> const FrameTiming& { return c.timing; });
}

const core::PoseConfig& SensorConfig::pose() const {
  return WithActive([](const auto& c) -> const core::PoseConfig& { return c.pose; });
}

const char* SensorConfig::modality() const {
  switch (type) {
    case SensorType::kLidar:
      return "lidar";
    case SensorType::kFmcwRadar:
      return "radar";
    default:
      return "camera";
  }
}

double SensorConfig::RaysPerFrame() const {
  return WithActive([](const auto& c) { return c.RaysPerFrame(); });
}

double SensorConfig::RawBytesPerFrame() const {
  return WithActive([](const auto& c) { return c.RawBytesPerFrame(); });
}

template <class V>
void Visit(V& v, SensorConfig& c) {
  v.Enum("type", c.type,
         {{"fisheye_stereo", SensorType::kFisheyeStereo},
          {"lidar", SensorType::kLidar},
          {"fmcw_radar", SensorType::kFmcwRadar}});
  // The type's keys sit beside "type" in the same object.
  switch (c.type) {
    case SensorType::kFisheyeStereo:
      Visit(v, c.fisheye);
      break;
    case SensorType::kLidar:
      Visit(v, c.lidar);
      break;
    case SensorType::kFmcwRadar:
      Visit(v, c.radar);
      break;
  }
}
UAVSIM_INSTANTIATE_VISIT(SensorConfig);

}  // namespace uavsim::sensors
