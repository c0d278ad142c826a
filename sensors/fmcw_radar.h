// FMCW radar: ray-cast scatterers -> complex IF cube -> (RadarProcessor)
// point cloud (paper Sec. IV-A; issue 4).
//
// Conventions shared by synthesis and processing (tests rely on them):
// - Radar frame R: REP 103 body frame at the pose (x boresight, y left, z up).
// - Virtual array in the R y-z plane: element (ix, iy) at
//   p = (0, ix * dx, iy * dy), dx = spacing_x_wavelengths * lambda (likewise dy).
// - Direction to a target u = (cos el cos az, cos el sin az, sin el): azimuth
//   az in the x-y plane from x toward y, elevation el from that plane toward z.
// - Fast time t_s = s / fs (s = 0 .. adc_samples - 1) within a chirp; chirp c
//   starts at c * T_c with T_c = chirp_duration + idle_time.
// - A scatterer k at range R_k (at the frame's start), radial velocity v_k
//   (positive = receding) and direction u_k contributes
//     a_k exp(j [2 pi f_b t_s + 4 pi R_k / lambda + 2 pi (2 v_k / lambda) c T_c
//                + 2 pi (p . u_k) / lambda])
//   with beat frequency f_b = 2 K R_k / c, K = bandwidth / chirp_duration,
//   and |a_k|^2 the received power from the radar equation
//   P_r = P_t G^2 lambda^2 sigma / ((4 pi)^3 R^4) relative to the noise power
//   k T B F per sample (B = sample rate). The spatial phase is the paper's
//   Delta phi_x, Delta phi_y with the angles measured as above.
// - Range resolution c / (2 B_sweep); velocity resolution
//   lambda / (2 N_chirps T_c); maximum range fs c / (2 K).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "sensors/fmcw_radar_config.h"
#include "sensors/frames.h"
#include "sensors/radar_cube.h"
#include "sensors/raycast_scene.h"
#include "sim/core/rng.h"
#include "sim/core/weather.h"

namespace uavsim::sensors {

// A point scatterer in the world frame.
struct Scatterer {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  double rcs_m2 = 0.0;
};

class FmcwRadar {
 public:
  FmcwRadar(const FmcwRadarConfig& config, RaycastScene& scene);

  // Rays over the field of view at ray_density_deg; hits become scatterers
  // with an RCS from the material's radar class and the incidence, merged
  // within a resolution cell. The caller has posed the scene at t_s.
  std::vector<Scatterer> FindScatterers(double t_s) const;

  // The IF cube of `scatterers` (radar equation amplitudes, thermal noise
  // kTBF, rain attenuation and clutter from `weather`), noise from `noise`.
  RadarCube Synthesize(const std::vector<Scatterer>& scatterers, const core::WeatherConfig& weather,
                       core::RngStream& noise) const;

  const FmcwRadarConfig& config() const { return config_; }
  const Eigen::Isometry3d& X_WR() const { return X_WR_; }

 private:
  FmcwRadarConfig config_;
  RaycastScene& scene_;
  Eigen::Isometry3d X_WR_;
};

}  // namespace uavsim::sensors
