// Weather as plain data, shared by every consumer (camera, LiDAR, radar,
// uplink) so one scenario value reaches all of them consistently.
#pragma once

#include <optional>

namespace uavsim::core {

struct WeatherConfig {
  double rain_mm_h = 0.0;                  // rain rate; 0 = dry
  std::optional<double> fog_visibility_m;  // meteorological optical range; unset = no fog
  double illumination = 1.0;               // 1 = overcast day; 0.01 = night; scales exposure
};

template <class V>
void Visit(V& v, WeatherConfig& c);

}  // namespace uavsim::core
