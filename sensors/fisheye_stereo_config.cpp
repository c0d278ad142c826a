#include "sensors/fisheye_stereo_config.h"

#include "core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

template <class V>
void Visit(V& v, FisheyeStereoConfig& c) {
  VisitTiming(v, c.timing);
  v.Object("pose", c.pose);
  v("width_px", c.width_px, Rule::Range(16, 8192));
  v("height_px", c.height_px, Rule::Range(16, 8192));
  v("xi", c.xi, Rule::Range(0.0, 10.0));
  v("fx_px", c.fx_px, Rule::Positive(1e5));
  v("fy_px", c.fy_px, Rule::Positive(1e5));
  v("cx_px", c.cx_px, Rule::Range(0.0, 8192.0));
  v("cy_px", c.cy_px, Rule::Range(0.0, 8192.0));
  v.Check(c.cx_px <= c.width_px, "cx_px",
          "cx_px must lie inside the image (width_px " + std::to_string(c.width_px) + ")");
  v.Check(c.cy_px <= c.height_px, "cy_px",
          "cy_px must lie inside the image (height_px " + std::to_string(c.height_px) + ")");
  v("k1", c.k1, Rule::Range(-10.0, 10.0));
  v("k2", c.k2, Rule::Range(-10.0, 10.0));
  v("p1", c.p1, Rule::Range(-1.0, 1.0));
  v("p2", c.p2, Rule::Range(-1.0, 1.0));
  v("k3", c.k3, Rule::Range(-10.0, 10.0));
  v("baseline_m", c.baseline_m, Rule::Positive(10.0));
  v("sun_azimuth_deg", c.sun_azimuth_deg, Rule::Range(-360.0, 360.0));
  v("sun_elevation_deg", c.sun_elevation_deg, Rule::Range(-90.0, 90.0));
  v("exposure", c.exposure, Rule::Positive(1e4));
  v("full_well_e", c.full_well_e, Rule::Range(1.0, 1e7));
  v("read_noise_e", c.read_noise_e, Rule::NonNegative(1e4));
  v("gamma", c.gamma, Rule::Range(1.0, 3.0));
  v("sensor_noise", c.sensor_noise);
}
UAVSIM_INSTANTIATE_VISIT(FisheyeStereoConfig);

}  // namespace uavsim::sensors
