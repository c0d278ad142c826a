#include "core/rain_attenuation.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>

using uavsim::core::Polarization;
using uavsim::core::RainCoefficientsFor;
using uavsim::core::RainCoefficientsHorizontal;
using uavsim::core::RainCoefficientsTilted;
using uavsim::core::RainCoefficientsVertical;
using uavsim::core::RainSpecificAttenuationDbPerKm;

namespace {

// Rows of Recommendation ITU-R P.838-3, Table 5: f (GHz), kH, alphaH, kV, alphaV.
struct Row {
  double f_ghz, k_h, alpha_h, k_v, alpha_v;
};
constexpr Row kTable5[] = {
    {1, 0.0000259, 0.9691, 0.0000308, 0.8592}, {4, 0.0001071, 1.6009, 0.0002461, 1.2476},
    {5, 0.0002162, 1.6969, 0.0002428, 1.5317}, {10, 0.01217, 1.2571, 0.01129, 1.2156},
    {20, 0.09164, 1.0568, 0.09611, 0.9847},    {28, 0.2051, 0.9679, 0.1964, 0.9277},
    {30, 0.2403, 0.9485, 0.2291, 0.9129},      {60, 0.8606, 0.7656, 0.8515, 0.7486},
    {80, 1.1704, 0.7115, 1.1668, 0.7021},      {100, 1.3671, 0.6815, 1.3680, 0.6765},
    {300, 1.6286, 0.6296, 1.6286, 0.6262},     {1000, 1.3795, 0.6396, 1.3822, 0.6365},
};

}  // namespace

TEST_CASE("RainAttenuation: the P.838-3 regression reproduces Table 5", "[core]") {
  for (const Row& row : kTable5) {
    INFO(row.f_ghz << " GHz");
    const auto h = RainCoefficientsHorizontal(row.f_ghz);
    const auto v = RainCoefficientsVertical(row.f_ghz);
    // The table prints four significant digits of k and four decimals of alpha.
    CHECK(h.k == Approx(row.k_h).epsilon(1e-3));
    CHECK(v.k == Approx(row.k_v).epsilon(1e-3));
    CHECK(h.alpha == Approx(row.alpha_h).margin(1.5e-4));
    CHECK(v.alpha == Approx(row.alpha_v).margin(1.5e-4));
  }
}

TEST_CASE("RainAttenuation: 28 GHz at 25 mm/h", "[core]") {
  // From the Table 5 row: gamma = k R^alpha.
  const double g_h = 0.2051 * std::pow(25.0, 0.9679);  // 4.62 dB/km: the "about 4.6"
  const double g_v = 0.1964 * std::pow(25.0, 0.9277);  // 3.89 dB/km
  CHECK(RainSpecificAttenuationDbPerKm(28, 25, Polarization::kHorizontal) ==
        Approx(g_h).epsilon(2e-3));
  CHECK(RainSpecificAttenuationDbPerKm(28, 25, Polarization::kVertical) ==
        Approx(g_v).epsilon(2e-3));
  CHECK(RainSpecificAttenuationDbPerKm(28, 25, Polarization::kHorizontal) ==
        Approx(4.6).margin(0.05));
  // Circular (tau = 45 deg), eqs. (4)-(5): k = (kH + kV)/2, alpha = (kH aH + kV aV)/(2k).
  const double k_c = (0.2051 + 0.1964) / 2;
  const double a_c = (0.2051 * 0.9679 + 0.1964 * 0.9277) / (2 * k_c);
  CHECK(RainSpecificAttenuationDbPerKm(28, 25, Polarization::kCircular) ==
        Approx(k_c * std::pow(25.0, a_c)).epsilon(2e-3));
  CHECK(RainSpecificAttenuationDbPerKm(28, 0, Polarization::kHorizontal) == 0.0);
}

TEST_CASE("RainAttenuation: polarisation tilt and path elevation", "[core]") {
  const auto h = RainCoefficientsHorizontal(40);
  const auto v = RainCoefficientsVertical(40);
  // tau = 0 and 90 deg on a horizontal path are H and V.
  CHECK(RainCoefficientsTilted(40, 0, 0).k == Approx(h.k));
  CHECK(RainCoefficientsTilted(40, 0, 0).alpha == Approx(h.alpha));
  CHECK(RainCoefficientsTilted(40, 0, 90).k == Approx(v.k));
  CHECK(RainCoefficientsTilted(40, 0, 90).alpha == Approx(v.alpha));
  // A vertical path (theta = 90 deg) sees the mean whatever the tilt.
  for (auto pol : {Polarization::kHorizontal, Polarization::kVertical, Polarization::kCircular}) {
    CHECK(RainCoefficientsFor(40, pol, 90).k == Approx((h.k + v.k) / 2));
    CHECK(RainCoefficientsFor(40, pol, 90).alpha ==
          Approx((h.k * h.alpha + v.k * v.alpha) / (h.k + v.k)));
  }
}

TEST_CASE("RainAttenuation: arguments outside the recommendation throw", "[core]") {
  CHECK_THROWS_AS(RainCoefficientsHorizontal(0.5), std::invalid_argument);
  CHECK_THROWS_AS(RainCoefficientsVertical(1001), std::invalid_argument);
  CHECK_THROWS_AS(RainCoefficientsHorizontal(std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(RainCoefficientsTilted(28, 91, 0), std::invalid_argument);
  CHECK_THROWS_AS(RainSpecificAttenuationDbPerKm(28, -1, Polarization::kVertical),
                  std::invalid_argument);
}
