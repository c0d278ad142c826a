// The atmosphere as a 905 nm LiDAR sees it: extinction in fog and rain (the
// shared optical atmosphere of sensors/atmosphere.h at kLidarWavelengthNm)
// and the mean and largest weather echoes a beam can receive, as functions
// of range. Plain math (no Embree): the LiDAR model (lidar.h, where the laws
// and their sources are given) draws its echoes from these, and a sensing
// node that knows its sensor and the weather tells weather echoes from
// hard targets with them (pipeline/node/lidar_preprocessor.h).
//
// Powers are in the LiDAR model's normalised units (m^-2): a Lambertian
// target of reflectivity rho at range R, head-on, in clear air past full
// overlap returns rho / R^2. Ranges in metres from the sensor.
#pragma once

#include "core/rng.h"
#include "core/weather.h"
#include "sensors/atmosphere.h"
#include "sensors/lidar_config.h"

namespace uavsim::sensors {

// Extinction coefficients at 905 nm, in 1/m: FogExtinctionPerM(visibility_m,
// kLidarWavelengthNm) and OpticalExtinctionPerM(weather, kLidarWavelengthNm)
// of sensors/atmosphere.h (Kim et al. 2001 for fog; rain, Marshall-Palmer
// drops with Q_ext = 2, is RainExtinctionPerM there at any wavelength).
double FogExtinctionPerM(double visibility_m);
double AtmosphericExtinctionPerM(const core::WeatherConfig& weather);
// Water's Fresnel reflectance at 905 nm, ((n - 1) / (n + 1))^2 with n = 1.328.
constexpr double kWaterFresnel = 0.0199;
// Fog backscatter coefficient times visibility (Rasshofer et al. 2011), 1/sr.
constexpr double kFogBackscatterTimesVisibility = 0.046;

// Transmitter/receiver overlap xi(r): 0 below min_range_m, linear to 1 at
// full_overlap_range_m (Hahner et al. 2021).
double LidarOverlap(const LidarConfig& c, double range_m);
// The receiver's detection threshold P_th = reference_reflectivity / max_range_m^2.
double LidarThreshold(const LidarConfig& c);
// The received power an intensity stands for (intensity = min(1, P
// saturation_range_m^2), lidar.h); +infinity for a saturated return.
double LidarPowerOfIntensity(const LidarConfig& c, double intensity);

// Mean fog echo S(r) = rho_v xi(r) exp(-2 alpha r) / r^2 with rho_v =
// pi beta c tau / 2 (one range cell of fog, Hahner et al. 2021); 0 without fog.
double FogEchoMeanPower(const LidarConfig& c, const core::WeatherConfig& w, double range_m);
// Speckle cells a beam's fog echo sums: M = max(1, (D theta / lambda)^2),
// D = receiver_aperture_mm, theta = beam_divergence_mrad (full angle),
// lambda = 905 nm (lidar.h). 1 when the aperture is below one speckle cell.
double FogSpeckleCells(const LidarConfig& c);
// One beam's fog echo in units of its mean, the sum of M independent
// fully developed speckle cells: Gamma(M, 1/M), mean 1, variance 1 / M
// (Goodman 2007, integrated speckle). Marsaglia & Tsang's (2000) method on
// `rng` (normal and uniform draws only): deterministic for a given stream.
// Requires M >= 1.
double FogSpeckleFade(double cells, core::RngStream& rng);

// The strongest echo a raindrop can return at r, a drop filling the beam:
// kWaterFresnel xi(r) exp(-2 alpha r) / r^2 (LISA, Kilic et al. 2021); 0 without rain.
double RainEchoMaxPower(const LidarConfig& c, const core::WeatherConfig& w, double range_m);

}  // namespace uavsim::sensors
