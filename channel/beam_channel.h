// The downlink channel from the base station's UPA to the UAV's single
// antenna, h = sum_p alpha_p a(theta_p, phi_p) (paper Sec. VI-C), built from
// the world's geometry through a PathOracle.
//
// Paths (BaseStationConfig::path_model):
//   - direct (line of sight): from the array centre to the UAV; absent when
//     PathOracle::Blocked(bs, uav) is true.
//   - "image": one single-bounce specular path per facade of
//     PathOracle::Reflectors() for which the base station and the UAV are
//     both on the facade's outer side, the reflection point lies inside the
//     facade rectangle, and neither leg is blocked. Image method: the UAV is
//     mirrored in the facade plane, uav' = uav - 2 ((uav - c) . n) n; the
//     path length is |uav' - bs|, the departure direction is
//     (uav' - bs) / |uav' - bs|, and the reflection point is where the
//     segment bs -> uav' crosses the plane. Each leg is tested from/to a point
//     1 mm off the wall on its outer side, so the wall itself never blocks.
//   - "clusters": the direct path plus ClusterConfig::count scattered paths
//     around its direction (base_station_config.h), drawn from the RNG
//     stream passed to Realize; they stay when the direct path is blocked.
// Paths that leave behind the panel (departure direction with z_A <= 0) are
// dropped: a panel radiates into its front half-space only.
//
// Complex amplitude of path p of length l_p (metres, both legs for a
// reflection), at wavelength lambda = c / f_c:
//   alpha_p = Gamma_p (lambda / (4 pi l_p)) 10^(-A l_p / 20000) exp(-j 2 pi l_p / lambda)
// with the Friis free-space amplitude (free-space path loss (4 pi l / lambda)^2),
// A the rain's specific attenuation in dB/km over the whole path, Gamma = 1
// for the direct path and Gamma = -10^(-L_material / 20) for a reflection
// (L: ReflectionLossConfig; the sign is the phase flip of a reflection at a
// denser medium). A cluster path carries |alpha|^2 = g_fs(d) 10^(-A d /
// 10000) / (K count) with a uniform random phase (d: direct-path length).
//
// Normalisation (what "SNR" on the rate curve means). The returned h is
//   h = (1 / sqrt(g_ref)) sum_p alpha_p a(theta_p, phi_p),
//   g_ref = (lambda / (4 pi d_ref))^2,
// with d_ref the current true base-station-to-UAV distance
// (SnrReference::kLosFreeSpace, default) or reference_distance_m
// (kReferenceDistance). The downlink y = h^H f s + n with a unit-norm beam f
// then has receive SNR = SNR * gamma, gamma = |h^H f|^2, where SNR = P_tx
// g_ref / sigma^2 is the SNR the reference path would give one antenna. With
// the default a perfect beam on a clear, dry direct path has gamma = Mx My
// exactly; blockage, rain, reflections and pointing errors move gamma from
// there. Rain, blocking and reflection losses all count against the dry
// free-space reference.
//
// Deterministic: Realize depends only on its inputs (and, for "clusters", on
// the state of the stream it is given).
#pragma once

#include <Eigen/Core>
#include <complex>
#include <vector>

#include "channel/base_station_config.h"
#include "channel/path_oracle.h"
#include "channel/upa.h"
#include "core/rng.h"

namespace uavsim::channel {

// lambda = c / f_c.
double WavelengthM(double carrier_ghz);
// Friis free-space power gain between isotropic antennas, (lambda / (4 pi d))^2;
// its inverse is the free-space path loss.
double FreeSpaceGain(double distance_m, double wavelength_m);

enum class PathKind { kLineOfSight, kReflection, kCluster };

struct DownlinkPath {
  PathKind kind = PathKind::kLineOfSight;
  std::complex<double> alpha;                              // absolute amplitude gain (above)
  double length_m = 0.0;                                   // propagation length, all legs
  Eigen::Vector3d departure_W = Eigen::Vector3d::UnitZ();  // unit, world frame
  Eigen::Vector3d departure_A = Eigen::Vector3d::UnitZ();  // unit, array frame A
  DirectionAngles angles;                                  // of departure_A (upa.h)
  Eigen::Vector3d bounce_m = Eigen::Vector3d::Zero();      // reflection point (kReflection)
  int facade = -1;                                         // index in Reflectors() (kReflection)
};

struct DownlinkChannel {
  std::vector<DownlinkPath> paths;  // direct path first when present, then reflections / clusters
  Eigen::VectorXcd h;               // normalised channel (above), size Mx My
  double reference_gain = 0.0;      // g_ref, linear power gain
  bool los_blocked = false;         // the oracle blocked the direct path
};

class BeamChannel {
 public:
  // rain_db_per_km: the rain's specific attenuation at config.carrier_ghz
  // (ITU-R P.838, computed by the caller from the weather); 0 when dry.
  // Throws std::invalid_argument if it is negative or not finite.
  explicit BeamChannel(const BaseStationConfig& config, double rain_db_per_km = 0.0);

  // The channel to a single-antenna UAV at uav_m (world ENU, metres). `rng`
  // is required for path_model "clusters" (std::invalid_argument if null)
  // and unused otherwise. A UAV closer than 1 cm to the array centre has no
  // paths (h = 0).
  DownlinkChannel Realize(const Eigen::Vector3d& uav_m, const PathOracle& world,
                          core::RngStream* rng = nullptr) const;
  // Same, reusing `out`'s storage.
  void RealizeInto(const Eigen::Vector3d& uav_m, const PathOracle& world, core::RngStream* rng,
                   DownlinkChannel* out) const;

  const Upa& upa() const { return upa_; }
  const BaseStationConfig& config() const { return config_; }
  double wavelength_m() const { return lambda_m_; }
  double rain_db_per_km() const { return rain_db_per_km_; }

 private:
  // Path amplitude before the reflection/cluster factor: Friis, rain and phase.
  std::complex<double> Propagate(double length_m) const;
  // Fills the departure fields of `p` from a world direction; false if the
  // direction leaves behind the panel.
  bool SetDeparture(const Eigen::Vector3d& dir_W, DownlinkPath* p) const;

  BaseStationConfig config_;
  Upa upa_;
  double lambda_m_;
  double rain_db_per_km_;
  double rain_neper_per_m_;
  // |Gamma| per built-in material index; the last entry is "other".
  std::vector<double> reflection_amplitude_;
};

}  // namespace uavsim::channel
