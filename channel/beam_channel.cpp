#include "channel/beam_channel.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/physical_constants.h"

namespace uavsim::channel {
namespace {

using core::kPi;
using core::kSpeedOfLight_mps;
constexpr double kMinDistanceM = 0.01;
// Off-wall offset of a reflection point for the blockage test of its legs:
// the point lies on the wall's own triangles, which must not count.
constexpr double kWallOffsetM = 1e-3;

double DbToPower(double db) { return std::pow(10.0, db / 10.0); }
double DbToAmplitude(double db) { return std::pow(10.0, db / 20.0); }

}  // namespace

double WavelengthM(double carrier_ghz) { return kSpeedOfLight_mps / (carrier_ghz * 1e9); }

double FreeSpaceGain(double distance_m, double wavelength_m) {
  const double a = wavelength_m / (4.0 * kPi * distance_m);
  return a * a;
}

BeamChannel::BeamChannel(const BaseStationConfig& config, double rain_db_per_km)
    : config_(config),
      upa_(Upa::FromConfig(config)),
      lambda_m_(WavelengthM(config.carrier_ghz)),
      rain_db_per_km_(rain_db_per_km),
      // 10^(-A l / 20000) = exp(-(A ln 10 / 20000) l): one exp per path.
      rain_neper_per_m_(rain_db_per_km * std::log(10.0) / 20000.0) {
  if (!std::isfinite(rain_db_per_km) || rain_db_per_km < 0.0)
    throw std::invalid_argument("BeamChannel: rain_db_per_km must be finite and >= 0, got " +
                                std::to_string(rain_db_per_km));
  for (unsigned m = 0; m <= core::kBuiltinMaterialCount; ++m)
    reflection_amplitude_.push_back(DbToAmplitude(-ReflectionLossDb(config.reflection_loss_db, m)));
}

std::complex<double> BeamChannel::Propagate(double length_m) const {
  // Sec. VI-C alpha_p: Friis amplitude, rain over the whole path, carrier phase.
  const double amplitude =
      lambda_m_ / (4.0 * kPi * length_m) * std::exp(-rain_neper_per_m_ * length_m);
  return std::polar(amplitude, -2.0 * kPi * std::fmod(length_m / lambda_m_, 1.0));
}

bool BeamChannel::SetDeparture(const Eigen::Vector3d& dir_W, DownlinkPath* p) const {
  p->departure_W = dir_W.normalized();
  p->departure_A = upa_.ToArrayFrame(p->departure_W);
  if (p->departure_A.z() <= 0.0) return false;
  p->angles = Upa::Angles(p->departure_A);
  return true;
}

DownlinkChannel BeamChannel::Realize(const Eigen::Vector3d& uav_m, const PathOracle& world,
                                     core::RngStream* rng) const {
  DownlinkChannel out;
  RealizeInto(uav_m, world, rng, &out);
  return out;
}

void BeamChannel::RealizeInto(const Eigen::Vector3d& uav_m, const PathOracle& world,
                              core::RngStream* rng, DownlinkChannel* out) const {
  if (config_.path_model == PathModel::kClusters && rng == nullptr)
    throw std::invalid_argument("BeamChannel: path_model \"clusters\" needs an RNG stream");
  out->paths.clear();
  out->los_blocked = false;
  out->h.setZero(upa_.size());

  const Eigen::Vector3d& bs = config_.position_m;
  const Eigen::Vector3d to_uav = uav_m - bs;
  const double d = to_uav.norm();
  const double d_ref =
      config_.snr_reference == SnrReference::kLosFreeSpace ? d : config_.reference_distance_m;
  out->reference_gain = FreeSpaceGain(std::max(d_ref, kMinDistanceM), lambda_m_);
  if (d < kMinDistanceM) return;

  DownlinkPath los;
  los.kind = PathKind::kLineOfSight;
  los.length_m = d;
  los.alpha = Propagate(d);
  const bool los_in_front = SetDeparture(to_uav, &los);
  out->los_blocked = world.Blocked(bs, uav_m);
  if (los_in_front && !out->los_blocked) out->paths.push_back(los);

  if (config_.path_model == PathModel::kImage) {
    const std::vector<core::Facade>& facades = world.Reflectors();
    for (std::size_t i = 0; i < facades.size(); ++i) {
      const core::Facade& f = facades[i];
      const double s_bs = (bs - f.center_m).dot(f.normal);
      const double s_uav = (uav_m - f.center_m).dot(f.normal);
      if (s_bs <= 0.0 || s_uav <= 0.0) continue;
      const Eigen::Vector3d image = uav_m - 2.0 * s_uav * f.normal;
      const Eigen::Vector3d bounce = bs + (s_bs / (s_bs + s_uav)) * (image - bs);
      const Eigen::Vector3d v_axis = f.normal.cross(f.u_axis);
      const Eigen::Vector3d in_plane = bounce - f.center_m;
      if (std::abs(in_plane.dot(f.u_axis)) > f.half_width_m ||
          std::abs(in_plane.dot(v_axis)) > f.half_height_m)
        continue;
      DownlinkPath p;
      p.kind = PathKind::kReflection;
      p.facade = static_cast<int>(i);
      p.bounce_m = bounce;
      p.length_m = (image - bs).norm();
      if (!SetDeparture(image - bs, &p)) continue;
      const Eigen::Vector3d off_wall = bounce + kWallOffsetM * f.normal;
      if (world.Blocked(bs, off_wall) || world.Blocked(off_wall, uav_m)) continue;
      const std::size_t m = std::min<std::size_t>(f.material, core::kBuiltinMaterialCount);
      p.alpha = -reflection_amplitude_[m] * Propagate(p.length_m);
      out->paths.push_back(p);
    }
  } else if (config_.path_model == PathModel::kClusters) {
    const ClusterConfig& c = config_.clusters;
    const Eigen::Vector3d u = to_uav / d;
    Eigen::Vector3d e1 = Eigen::Vector3d::UnitZ().cross(u);
    e1 = e1.norm() > 1e-9 ? e1.normalized() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d e2 = u.cross(e1);
    const double power = FreeSpaceGain(d, lambda_m_) * DbToPower(-rain_db_per_km_ * d / 1000.0) /
                         (DbToPower(c.k_factor_db) * c.count);
    const double sigma_az = c.azimuth_spread_deg * kPi / 180.0;
    const double sigma_el = c.elevation_spread_deg * kPi / 180.0;
    for (int k = 0; k < c.count; ++k) {
      // Draw all three numbers whatever happens to the path, so one
      // cluster's fate never shifts the next cluster's draws.
      const double da = rng->Normal(0.0, sigma_az);
      const double de = rng->Normal(0.0, sigma_el);
      const double phase = rng->Uniform(0.0, 2.0 * kPi);
      const Eigen::Vector3d turned = std::cos(da) * u + std::sin(da) * e1;
      DownlinkPath p;
      p.kind = PathKind::kCluster;
      p.length_m = d;
      if (!SetDeparture(std::cos(de) * turned + std::sin(de) * e2, &p)) continue;
      p.alpha = std::polar(std::sqrt(power), phase);
      out->paths.push_back(p);
    }
  }

  Eigen::VectorXcd a;
  const double scale = 1.0 / std::sqrt(out->reference_gain);
  for (const DownlinkPath& p : out->paths) {
    upa_.SteeringInto(p.departure_A, &a);
    out->h += (scale * p.alpha) * a;  // Sec. VI-C: h = sum_p alpha_p a(theta_p, phi_p)
  }
}

}  // namespace uavsim::channel
