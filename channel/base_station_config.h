// The base station: position and its uniform planar array for the downlink
// beam that relays through the UAV (paper Sec. VI-C).
#pragma once

#include <Eigen/Core>

namespace uavsim::channel {

struct UpaConfig {
  int mx = 8;
  int my = 8;
  double spacing_wavelengths = 0.5;
};

struct BaseStationConfig {
  Eigen::Vector3d position_m{0.0, 0.0, 10.0};
  UpaConfig upa;
  double carrier_ghz = 28.0;
};

template <class V>
void Visit(V& v, UpaConfig& c);
template <class V>
void Visit(V& v, BaseStationConfig& c);

}  // namespace uavsim::channel
