#include "core/weather.h"

#include "core/json_io.h"

namespace uavsim::core {

template <class V>
void Visit(V& v, WeatherConfig& c) {
  v("rain_mm_h", c.rain_mm_h,
    Rule::NonNegative(300.0));  // 300 mm/h exceeds any recorded hourly rate
  v("fog_visibility_m", c.fog_visibility_m, Rule{1.0, 1e5, false, false});
  v("illumination", c.illumination, Rule::Range(0.0, 10.0));
}
UAVSIM_INSTANTIATE_VISIT(WeatherConfig);

}  // namespace uavsim::core
