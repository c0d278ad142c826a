// The base station: position and uniform planar array (UPA) of the downlink
// beam that relays through the UAV (paper Sec. VI-C), and the choices of the
// downlink channel model (channel/beam_channel.h) and beams
// (channel/beamformer.h).
//
// Array frame A (channel/upa.h): z_A is the boresight (the panel's outward
// normal), x_A is horizontal, y_A = z_A x x_A. The mx elements of a row run
// along x_A, the my elements of a column along y_A. The boresight is given by
// its azimuth (from world +x towards +y, i.e. from east towards north) and
// its elevation above the horizon; x_A = (-sin az, cos az, 0) is the
// horizontal direction 90 deg counter-clockwise from the boresight's azimuth.
// The default boresight is the zenith: the default orbit circles above the
// base station, so an upward panel keeps it in front at every point.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace uavsim::channel {

struct UpaConfig {
  int mx = 8;  // elements along x_A
  int my = 8;  // elements along y_A
  double spacing_wavelengths = 0.5;
};

// Where the downlink's paths come from.
enum class PathModel {
  kLosOnly,   // the direct path only (blocked when the world says so)
  kImage,     // direct path + single-bounce reflections off building facades (image method)
  kClusters,  // direct path + statistical scattered paths around it (ClusterConfig)
};

// What "SNR" on the rate-vs-SNR curve means (channel/beam_channel.h).
enum class SnrReference {
  // The SNR of the unblocked, dry, free-space direct path into one antenna at
  // the UAV's current true distance: a perfect beam on a clear direct path
  // then has gamma = mx * my, whatever the distance.
  kLosFreeSpace,
  // The SNR of one antenna in dry free space at reference_distance_m: range
  // changes along the trajectory show in gamma as (reference_distance / d)^2.
  kReferenceDistance,
};

// Power lost at one specular reflection, per built-in material
// (core::BuiltinMaterial); any other material index uses other_db. Defaults
// are round values of the order of 28 GHz building-material measurements (a
// few dB for glass and concrete, near zero for metal); set them per site.
struct ReflectionLossConfig {
  double ground_db = 6.0;
  double concrete_db = 6.0;
  double glass_db = 3.0;
  double metal_db = 1.0;
  double foliage_db = 15.0;
  double other_db = 10.0;
};

// Statistical scattered paths (path_model "clusters"): `count` paths whose
// departure directions are the direct path's, tilted by independent normal
// angles of standard deviation azimuth_spread_deg (horizontally) and
// elevation_spread_deg (vertically); together they carry 1/K of the
// free-space direct path's power (Rician K-factor k_factor_db), split
// equally, each with a uniform random phase. Drawn anew for every channel
// realisation from the channel's own RNG stream.
struct ClusterConfig {
  int count = 3;
  double k_factor_db = 9.0;
  double azimuth_spread_deg = 10.0;
  double elevation_spread_deg = 5.0;
};

struct BaseStationConfig {
  Eigen::Vector3d position_m{0.0, 0.0, 10.0};  // array centre, world ENU
  UpaConfig upa;
  double carrier_ghz = 28.0;
  double boresight_az_deg = 0.0;
  double boresight_el_deg = 90.0;
  PathModel path_model = PathModel::kImage;
  SnrReference snr_reference = SnrReference::kLosFreeSpace;
  double reference_distance_m = 100.0;  // used by SnrReference::kReferenceDistance
  ReflectionLossConfig reflection_loss_db;
  ClusterConfig clusters;
  // Beam families scored on the rate curve: "steered" (f = a(estimate
  // direction) / sqrt(N): beams "perfect", and one per localization method)
  // and "dft" (best codeword of an oversampled 2-D DFT codebook: beams
  // "dft_perfect", "dft_<method>").
  std::vector<std::string> beams{"steered"};
  int dft_oversampling = 2;  // codebook size (O mx) x (O my)
};

// Power loss in dB of a reflection off material index `material`
// (core::BuiltinMaterial numbering).
double ReflectionLossDb(const ReflectionLossConfig& c, unsigned material);

template <class V>
void Visit(V& v, UpaConfig& c);
template <class V>
void Visit(V& v, ReflectionLossConfig& c);
template <class V>
void Visit(V& v, ClusterConfig& c);
template <class V>
void Visit(V& v, BaseStationConfig& c);

}  // namespace uavsim::channel
