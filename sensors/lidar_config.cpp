#include "sensors/lidar_config.h"

#include <cmath>

#include "sim/core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

double LidarConfig::RaysPerFrame() const {
  if (preset == LidarPreset::kLivoxRosette) return std::ceil(points_per_s / timing.rate_hz);
  return channels * std::ceil(360.0 / azimuth_resolution_deg);
}

template <class V>
void Visit(V& v, LidarConfig& c) {
  VisitTiming(v, c.timing);
  v.Object("pose", c.pose);
  v.Enum("preset", c.preset,
         {{"spinning32", LidarPreset::kSpinning32}, {"livox_rosette", LidarPreset::kLivoxRosette}});
  if (c.preset == LidarPreset::kSpinning32) {
    v("channels", c.channels, Rule::Range(1, 128));
    v("vertical_min_deg", c.vertical_min_deg, Rule::Range(-90.0, 90.0));
    v("vertical_max_deg", c.vertical_max_deg, Rule::Range(-90.0, 90.0));
    v.Check(c.vertical_min_deg < c.vertical_max_deg, "vertical_max_deg",
            "vertical_max_deg must be above vertical_min_deg");
    v("azimuth_resolution_deg", c.azimuth_resolution_deg, Rule::Range(0.001, 45.0));
  } else {
    v("points_per_s", c.points_per_s, Rule::Positive(1e9));
    v("fov_deg", c.fov_deg, Rule{0.0, 180.0, true, false});
  }
  v("max_range_m", c.max_range_m, Rule::Positive(10000.0));
  v("range_noise_m", c.range_noise_m, Rule::NonNegative(10.0));
  v("dropout", c.dropout, Rule{0.0, 1.0, false, true});
}
UAVSIM_INSTANTIATE_VISIT(LidarConfig);

}  // namespace uavsim::sensors
