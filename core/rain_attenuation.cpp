#include "core/rain_attenuation.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/physical_constants.h"

namespace uavsim::core {
namespace {

struct Gaussian {
  double a, b, c;
};

// P.838-3 Tables 1 to 4.
constexpr Gaussian kKh[] = {{-5.33980, -0.10008, 1.13098},
                            {-0.35351, 1.26970, 0.45400},
                            {-0.23789, 0.86036, 0.15354},
                            {-0.94158, 0.64552, 0.16817}};
constexpr double kKhM = -0.18961, kKhC = 0.71147;

constexpr Gaussian kKv[] = {{-3.80595, 0.56934, 0.81061},
                            {-3.44965, -0.22911, 0.51059},
                            {-0.39902, 0.73042, 0.11899},
                            {0.50167, 1.07319, 0.27195}};
constexpr double kKvM = -0.16398, kKvC = 0.63297;

constexpr Gaussian kAh[] = {{-0.14318, 1.82442, -0.55187},
                            {0.29591, 0.77564, 0.19822},
                            {0.32177, 0.63773, 0.13164},
                            {-5.37610, -0.96230, 1.47828},
                            {16.1721, -3.29980, 3.43990}};
constexpr double kAhM = 0.67849, kAhC = -1.95537;

constexpr Gaussian kAv[] = {{-0.07771, 2.33840, -0.76284},
                            {0.56727, 0.95545, 0.54039},
                            {-0.20238, 1.14520, 0.26809},
                            {-48.2991, 0.791669, 0.116226},
                            {48.5833, 0.791459, 0.116479}};
constexpr double kAvM = -0.053739, kAvC = 0.83433;

template <std::size_t N>
double Regression(const Gaussian (&terms)[N], double m, double c, double log_f) {
  double sum = m * log_f + c;
  for (const Gaussian& g : terms) {
    const double x = (log_f - g.b) / g.c;
    sum += g.a * std::exp(-x * x);
  }
  return sum;
}

double CheckedLogFrequency(double f_ghz) {
  if (!std::isfinite(f_ghz) || f_ghz < 1.0 || f_ghz > 1000.0)
    throw std::invalid_argument("ITU-R P.838-3: frequency must be in [1, 1000] GHz, got " +
                                std::to_string(f_ghz));
  return std::log10(f_ghz);
}

}  // namespace

const std::vector<std::pair<const char*, Polarization>>& PolarizationNames() {
  static const std::vector<std::pair<const char*, Polarization>> names = {
      {"horizontal", Polarization::kHorizontal},
      {"vertical", Polarization::kVertical},
      {"circular", Polarization::kCircular}};
  return names;
}

RainCoefficients RainCoefficientsHorizontal(double f_ghz) {
  const double log_f = CheckedLogFrequency(f_ghz);
  return {std::pow(10.0, Regression(kKh, kKhM, kKhC, log_f)), Regression(kAh, kAhM, kAhC, log_f)};
}

RainCoefficients RainCoefficientsVertical(double f_ghz) {
  const double log_f = CheckedLogFrequency(f_ghz);
  return {std::pow(10.0, Regression(kKv, kKvM, kKvC, log_f)), Regression(kAv, kAvM, kAvC, log_f)};
}

RainCoefficients RainCoefficientsTilted(double f_ghz, double elevation_deg, double tilt_deg) {
  if (!std::isfinite(elevation_deg) || elevation_deg < 0.0 || elevation_deg > 90.0)
    throw std::invalid_argument("ITU-R P.838-3: path elevation must be in [0, 90] deg, got " +
                                std::to_string(elevation_deg));
  if (!std::isfinite(tilt_deg))
    throw std::invalid_argument("ITU-R P.838-3: polarisation tilt must be finite");
  const RainCoefficients h = RainCoefficientsHorizontal(f_ghz);
  const RainCoefficients v = RainCoefficientsVertical(f_ghz);
  const double cos_theta = std::cos(elevation_deg * kPi / 180.0);
  const double w = cos_theta * cos_theta * std::cos(2.0 * tilt_deg * kPi / 180.0);
  RainCoefficients out;
  out.k = 0.5 * (h.k + v.k + (h.k - v.k) * w);
  out.alpha = (h.k * h.alpha + v.k * v.alpha + (h.k * h.alpha - v.k * v.alpha) * w) / (2.0 * out.k);
  return out;
}

RainCoefficients RainCoefficientsFor(double f_ghz, Polarization polarization,
                                     double elevation_deg) {
  switch (polarization) {
    case Polarization::kHorizontal:
      return RainCoefficientsTilted(f_ghz, elevation_deg, 0.0);
    case Polarization::kVertical:
      return RainCoefficientsTilted(f_ghz, elevation_deg, 90.0);
    case Polarization::kCircular:
      return RainCoefficientsTilted(f_ghz, elevation_deg, 45.0);
  }
  throw std::invalid_argument("ITU-R P.838-3: unknown polarisation");
}

double RainSpecificAttenuationDbPerKm(double f_ghz, double rain_mm_h, Polarization polarization,
                                      double elevation_deg) {
  if (!std::isfinite(rain_mm_h) || rain_mm_h < 0.0)
    throw std::invalid_argument("ITU-R P.838-3: rain rate must be >= 0 mm/h, got " +
                                std::to_string(rain_mm_h));
  const RainCoefficients c = RainCoefficientsFor(f_ghz, polarization, elevation_deg);
  return rain_mm_h == 0.0 ? 0.0 : c.k * std::pow(rain_mm_h, c.alpha);
}

}  // namespace uavsim::core
