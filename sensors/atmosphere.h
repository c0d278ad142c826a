// The optical atmosphere: extinction of light by fog and rain, the one law
// the camera (at kVisibleWavelengthNm) and the LiDAR (at kLidarWavelengthNm)
// both attenuate by (Beer-Lambert: a path of d metres keeps e^(-alpha d)).
// Plain math (no Embree). Extinction coefficients alpha in 1/m, visibility
// (meteorological optical range) in m, rain rate in mm/h, wavelengths in nm.
//
//   fog:  alpha = (kKoschmieder / V) (lambda / 550 nm)^-q(V), Kim, McArthur &
//         Korevaar 2001 (Proc. SPIE 4214): Koschmieder's 2 % contrast
//         threshold at 550 nm, where visibility is defined, carried to other
//         wavelengths with Kim's q(V) (V in km): q = 1.6 above 50 km, 1.3 above
//         6 km, 0.16 V + 0.34 above 1 km, V - 0.5 above 0.5 km and 0 below
//         (dense fog scatters every wavelength alike). At 550 nm alpha is
//         exactly kKoschmieder / V.
//   rain: alpha = pi N0 / Lambda^3 = 3.65e-4 R^0.63 m^-1: Marshall-Palmer
//         drops N(D) = N0 exp(-Lambda D) (Marshall & Palmer 1948), N0 =
//         kMarshallPalmerN0, Lambda = 4.1 R^-0.21 mm^-1, each removing twice
//         its cross-section from the beam (the large-drop extinction
//         efficiency Q_ext = 2, the limit LISA's Mie integral reaches for
//         raindrops, Kilic et al. 2021): alpha = integral of 2 (pi D^2 / 4)
//         N(D) dD. Drops are thousands of wavelengths across, so alpha is the
//         same at 550 nm and 905 nm. 2.8e-3 /m at 25 mm/h; 1.2 to 1.5 times
//         the free-space-optics law 1.076 R^0.67 dB/km (Carbonneau & Wisely
//         1998) over 100 to 1 mm/h.
//   both: the sum (OpticalExtinctionPerM).
// No function throws; a visibility must be positive.
#pragma once

#include "core/weather.h"

namespace uavsim::sensors {

// -ln(0.02): Koschmieder's law, visibility is where a black target's
// contrast against the horizon sky falls to 2 %, alpha = kKoschmieder / V.
constexpr double kKoschmieder = 3.912;
// The wavelength visibility is defined at, and the camera's.
constexpr double kVisibleWavelengthNm = 550.0;
// The LiDAR's wavelength.
constexpr double kLidarWavelengthNm = 905.0;
// Marshall-Palmer drop-size intercept N0, m^-3 mm^-1.
constexpr double kMarshallPalmerN0 = 8000.0;

// Marshall-Palmer slope Lambda = 4.1 R^-0.21 (1/mm) at rain rate R (mm/h).
double MarshallPalmerLambdaPerMm(double rain_mm_h);

// Fog's extinction at visibility_m and wavelength_nm (Kim et al. 2001, above).
double FogExtinctionPerM(double visibility_m, double wavelength_nm);
// Rain's extinction at any optical wavelength (Marshall-Palmer, Q_ext = 2,
// above); 0 for rain_mm_h <= 0.
double RainExtinctionPerM(double rain_mm_h);
// Fog (if weather.fog_visibility_m is set) and rain together at wavelength_nm.
double OpticalExtinctionPerM(const core::WeatherConfig& weather, double wavelength_nm);

}  // namespace uavsim::sensors
