// Mathematical and physical constants, SI units: the one home for them (the
// CODATA 2018 exact values where the SI defines them).
#pragma once

namespace uavsim::core {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegToRad = kPi / 180.0;
inline constexpr double kRadToDeg = 180.0 / kPi;
inline constexpr double kSpeedOfLight_mps = 299792458.0;    // exact (SI)
inline constexpr double kBoltzmann_J_per_K = 1.380649e-23;  // exact (SI)

}  // namespace uavsim::core
