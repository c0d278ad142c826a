// Specific attenuation of rain, Recommendation ITU-R P.838-3 (03/2005),
// "Specific attenuation model for rain for use in prediction methods".
//
//   gamma_R = k R^alpha   [dB/km], R the rain rate in mm/h            (eq. 1)
//
// k and alpha for horizontal (H) and vertical (V) polarisation come from the
// recommendation's regression in f [GHz] (eqs. 2 and 3, Tables 1 to 4):
//
//   log10 k = sum_{j=1..4} a_j exp(-((log10 f - b_j) / c_j)^2) + m_k log10 f + c_k
//   alpha   = sum_{j=1..5} a_j exp(-((log10 f - b_j) / c_j)^2) + m_a log10 f + c_a
//
// and for any linear or circular polarisation and path elevation theta, with
// tau the polarisation tilt angle relative to the horizontal (eqs. 4 and 5):
//
//   k     = [kH + kV + (kH - kV) cos^2(theta) cos(2 tau)] / 2
//   alpha = [kH aH + kV aV + (kH aH - kV aV) cos^2(theta) cos(2 tau)] / (2 k)
//
// with tau = 0 deg for horizontal, 90 deg for vertical and 45 deg for circular
// polarisation. The regression reproduces the recommendation's Table 5 to its
// four printed digits. At 28 GHz (Table 5: kH = 0.2051, aH = 0.9679,
// kV = 0.1964, aV = 0.9277) and 25 mm/h it gives 4.63 dB/km horizontal,
// 3.89 dB/km vertical and 4.25 dB/km circular on a horizontal path.
//
// Valid range: 1 <= f <= 1000 GHz (the recommendation's), 0 <= R, 0 <= theta
// <= 90 deg. Out-of-range or non-finite arguments throw std::invalid_argument.
// Pure functions: no state, no randomness.
#pragma once

#include <utility>
#include <vector>

namespace uavsim::core {

enum class Polarization { kHorizontal, kVertical, kCircular };

// The scenario names of the polarisations ("horizontal", "vertical",
// "circular"), for a config Visit's Enum.
const std::vector<std::pair<const char*, Polarization>>& PolarizationNames();

// The power-law coefficients of gamma_R = k R^alpha.
struct RainCoefficients {
  double k = 0.0;      // (dB/km) / (mm/h)^alpha
  double alpha = 0.0;  // dimensionless
};

// Horizontal and vertical polarisation, eqs. (2) and (3).
RainCoefficients RainCoefficientsHorizontal(double f_ghz);
RainCoefficients RainCoefficientsVertical(double f_ghz);

// Any polarisation tilt tau and path elevation theta, eqs. (4) and (5).
RainCoefficients RainCoefficientsTilted(double f_ghz, double elevation_deg, double tilt_deg);

// The named polarisation (tau = 0, 90 or 45 deg) at path elevation theta.
RainCoefficients RainCoefficientsFor(double f_ghz, Polarization polarization,
                                     double elevation_deg = 0.0);

// gamma_R in dB/km, eq. (1).
double RainSpecificAttenuationDbPerKm(double f_ghz, double rain_mm_h, Polarization polarization,
                                      double elevation_deg = 0.0);

}  // namespace uavsim::core
