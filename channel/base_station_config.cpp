#include "channel/base_station_config.h"
#include "sim/core/json_io.h"

namespace uavsim::channel {

using core::Rule;

template <class V>
void Visit(V& v, UpaConfig& c) {
  v("mx", c.mx, Rule::Range(1, 1024));
  v("my", c.my, Rule::Range(1, 1024));
  v("spacing_wavelengths", c.spacing_wavelengths, Rule::Positive(10.0));
}
UAVSIM_INSTANTIATE_VISIT(UpaConfig);

template <class V>
void Visit(V& v, BaseStationConfig& c) {
  v("position_m", c.position_m, Rule::Range(-1e6, 1e6));
  v.Object("upa", c.upa);
  v("carrier_ghz", c.carrier_ghz, Rule::Range(0.1, 1000.0));
}
UAVSIM_INSTANTIATE_VISIT(BaseStationConfig);

}  // namespace uavsim::channel
