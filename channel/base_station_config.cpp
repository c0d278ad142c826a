#include "channel/base_station_config.h"

#include <algorithm>

#include "core/json_io.h"
#include "core/world_geometry.h"

namespace uavsim::channel {

using core::Rule;

double ReflectionLossDb(const ReflectionLossConfig& c, unsigned material) {
  switch (material) {
    case core::kMaterialGround:
      return c.ground_db;
    case core::kMaterialConcrete:
      return c.concrete_db;
    case core::kMaterialGlass:
      return c.glass_db;
    case core::kMaterialMetal:
      return c.metal_db;
    case core::kMaterialFoliage:
      return c.foliage_db;
    default:
      return c.other_db;
  }
}

template <class V>
void Visit(V& v, UpaConfig& c) {
  v("mx", c.mx, Rule::Range(1, 1024));
  v("my", c.my, Rule::Range(1, 1024));
  v("spacing_wavelengths", c.spacing_wavelengths, Rule::Positive(10.0));
}
UAVSIM_INSTANTIATE_VISIT(UpaConfig);

template <class V>
void Visit(V& v, ReflectionLossConfig& c) {
  v("ground_db", c.ground_db, Rule::NonNegative(100.0));
  v("concrete_db", c.concrete_db, Rule::NonNegative(100.0));
  v("glass_db", c.glass_db, Rule::NonNegative(100.0));
  v("metal_db", c.metal_db, Rule::NonNegative(100.0));
  v("foliage_db", c.foliage_db, Rule::NonNegative(100.0));
  v("other_db", c.other_db, Rule::NonNegative(100.0));
}
UAVSIM_INSTANTIATE_VISIT(ReflectionLossConfig);

template <class V>
void Visit(V& v, ClusterConfig& c) {
  v("count", c.count, Rule::Range(1, 64));
  v("k_factor_db", c.k_factor_db, Rule::Range(-30.0, 60.0));
  v("azimuth_spread_deg", c.azimuth_spread_deg, Rule::NonNegative(90.0));
  v("elevation_spread_deg", c.elevation_spread_deg, Rule::NonNegative(90.0));
}
UAVSIM_INSTANTIATE_VISIT(ClusterConfig);

template <class V>
void Visit(V& v, BaseStationConfig& c) {
  v("position_m", c.position_m, Rule::Range(-1e6, 1e6));
  v.Object("upa", c.upa);
  // ITU-R P.838-3's range: the downlink's rain attenuation is defined there.
  v("carrier_ghz", c.carrier_ghz, Rule::Range(1.0, 1000.0));
  v("boresight_az_deg", c.boresight_az_deg, Rule::Range(-360.0, 360.0));
  v("boresight_el_deg", c.boresight_el_deg, Rule::Range(-90.0, 90.0));
  // Like every tagged union in a scenario: the model first, then only its keys.
  v.Enum("path_model", c.path_model,
         {{"los_only", PathModel::kLosOnly},
          {"image", PathModel::kImage},
          {"clusters", PathModel::kClusters}});
  if (c.path_model == PathModel::kImage) v.Object("reflection_loss_db", c.reflection_loss_db);
  if (c.path_model == PathModel::kClusters) v.Object("clusters", c.clusters);
  v.Enum("snr_reference", c.snr_reference,
         {{"los_free_space", SnrReference::kLosFreeSpace},
          {"reference_distance", SnrReference::kReferenceDistance}});
  if (c.snr_reference == SnrReference::kReferenceDistance)
    v("reference_distance_m", c.reference_distance_m, Rule::Range(0.01, 1e6));
  static const std::vector<std::string> kBeamFamilies{"steered", "dft"};
  v("beams", c.beams, kBeamFamilies);
  const bool dft = std::find(c.beams.begin(), c.beams.end(), "dft") != c.beams.end();
  if (dft) v("dft_oversampling", c.dft_oversampling, Rule::Range(1, 16));
  v.Check(!c.beams.empty(), "beams", "beams must name at least one of \"steered\", \"dft\"");
}
UAVSIM_INSTANTIATE_VISIT(BaseStationConfig);

}  // namespace uavsim::channel
