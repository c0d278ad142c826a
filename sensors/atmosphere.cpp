#include "sensors/atmosphere.h"

#include <cmath>

#include "core/physical_constants.h"

namespace uavsim::sensors {

double MarshallPalmerLambdaPerMm(double rain_mm_h) { return 4.1 * std::pow(rain_mm_h, -0.21); }

double FogExtinctionPerM(double visibility_m, double wavelength_nm) {
  const double v_km = visibility_m / 1000.0;
  double q = 0.0;  // Kim et al. 2001: scattering in dense fog is wavelength independent
  if (v_km > 50.0)
    q = 1.6;
  else if (v_km > 6.0)
    q = 1.3;
  else if (v_km > 1.0)
    q = 0.16 * v_km + 0.34;
  else if (v_km > 0.5)
    q = v_km - 0.5;
  // At 550 nm the ratio is 1 and pow(1, -q) is exactly 1: Koschmieder's kKoschmieder / V.
  return kKoschmieder / visibility_m * std::pow(wavelength_nm / kVisibleWavelengthNm, -q);
}

double RainExtinctionPerM(double rain_mm_h) {
  if (rain_mm_h <= 0.0) return 0.0;
  const double lambda = MarshallPalmerLambdaPerMm(rain_mm_h);
  // 2 * (pi/4) * N0 * integral D^2 e^{-Lambda D} dD = pi N0 / Lambda^3, mm^2 m^-3 -> m^-1.
  return core::kPi * kMarshallPalmerN0 / (lambda * lambda * lambda) * 1e-6;
}

double OpticalExtinctionPerM(const core::WeatherConfig& weather, double wavelength_nm) {
  double alpha = RainExtinctionPerM(weather.rain_mm_h);
  if (weather.fog_visibility_m)
    alpha += FogExtinctionPerM(*weather.fog_visibility_m, wavelength_nm);
  return alpha;
}

}  // namespace uavsim::sensors
