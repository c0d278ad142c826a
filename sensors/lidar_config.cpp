#include "sensors/lidar_config.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/json_io.h"

namespace uavsim::sensors {

using core::FormatNumber;
using core::Rule;

double LidarConfig::RaysPerFrame() const {
  if (preset != LidarPreset::kSpinning32) return std::ceil(points_per_s / timing.rate_hz);
  return channels * std::ceil(360.0 / azimuth_resolution_deg);
}

double LidarConfig::FieldSolidAngleSr() const {
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  const auto band = [](double lo_deg, double hi_deg) {
    return 2.0 * 3.14159265358979323846 * (std::sin(hi_deg * kDeg) - std::sin(lo_deg * kDeg));
  };
  switch (preset) {
    case LidarPreset::kSpinning32:
      if (!vertical_angles_deg.empty())
        return band(*std::min_element(vertical_angles_deg.begin(), vertical_angles_deg.end()),
                    *std::max_element(vertical_angles_deg.begin(), vertical_angles_deg.end()));
      return band(vertical_min_deg, vertical_max_deg);
    case LidarPreset::kLivoxRosette:
      return 2.0 * 3.14159265358979323846 * (1.0 - std::cos(0.5 * fov_deg * kDeg));
    case LidarPreset::kLivoxMid360:
      return band(kMid360MinElevationDeg, kMid360MaxElevationDeg);
  }
  return 4.0 * 3.14159265358979323846;
}

template <class V>
void Visit(V& v, LidarConfig& c) {
  VisitTiming(v, c.timing);
  v.Object("pose", c.pose);
  v.Enum("preset", c.preset,
         {{"spinning32", LidarPreset::kSpinning32},
          {"livox_rosette", LidarPreset::kLivoxRosette},
          {"livox_mid360", LidarPreset::kLivoxMid360}});
  if (c.preset == LidarPreset::kSpinning32) {
    v("channels", c.channels, Rule::Range(1, 128));
    v("vertical_min_deg", c.vertical_min_deg, Rule::Range(-90.0, 90.0));
    v("vertical_max_deg", c.vertical_max_deg, Rule::Range(-90.0, 90.0));
    v.Check(c.vertical_min_deg < c.vertical_max_deg, "vertical_max_deg",
            "vertical_max_deg must be above vertical_min_deg");
    v("vertical_angles_deg", c.vertical_angles_deg, Rule::Range(-90.0, 90.0), 0, 128);
    v.Check(c.vertical_angles_deg.empty() ||
                static_cast<int>(c.vertical_angles_deg.size()) == c.channels,
            "vertical_angles_deg",
            "vertical_angles_deg has " + std::to_string(c.vertical_angles_deg.size()) +
                " angles but channels is " + std::to_string(c.channels) +
                " (give one angle per channel, or none)");
    v("azimuth_resolution_deg", c.azimuth_resolution_deg, Rule::Range(0.001, 45.0));
  } else {
    v("points_per_s", c.points_per_s, Rule::Positive(1e9));
    if (c.preset == LidarPreset::kLivoxRosette)
      v("fov_deg", c.fov_deg, Rule{0.0, 180.0, true, false});
  }
  v("max_range_m", c.max_range_m, Rule::Positive(10000.0));
  v("range_noise_m", c.range_noise_m, Rule::NonNegative(10.0));
  v("dropout", c.dropout, Rule{0.0, 1.0, false, true});
  v("reference_reflectivity", c.reference_reflectivity, Rule{0.0, 1.0, true, false});
  v("min_range_m", c.min_range_m, Rule::NonNegative(1000.0));
  v("full_overlap_range_m", c.full_overlap_range_m, Rule::NonNegative(1000.0));
  v.Check(
      c.full_overlap_range_m >= c.min_range_m, "full_overlap_range_m",
      "full_overlap_range_m must be at least min_range_m (" + FormatNumber(c.min_range_m) + " m)");
  v.Check(c.full_overlap_range_m < c.max_range_m, "full_overlap_range_m",
          "full_overlap_range_m must be below max_range_m (" + FormatNumber(c.max_range_m) + " m)");
  v("saturation_range_m", c.saturation_range_m, Rule::Positive(10000.0));
  v("pulse_width_ns", c.pulse_width_ns, Rule::Positive(1000.0));
  v("beam_divergence_mrad", c.beam_divergence_mrad, Rule::Positive(100.0));
  v("receiver_aperture_mm", c.receiver_aperture_mm, Rule::Positive(1000.0));
  v.Enum("return_mode", c.return_mode,
         {{"strongest", LidarReturnMode::kStrongest}, {"last", LidarReturnMode::kLast}});
  v("time_slices_per_frame", c.time_slices_per_frame, Rule::Range(1, 100000));
}
UAVSIM_INSTANTIATE_VISIT(LidarConfig);

}  // namespace uavsim::sensors
