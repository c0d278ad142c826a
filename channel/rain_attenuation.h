// Forwarding header: ITU-R P.838-3 now lives in sim/core/rain_attenuation.h
// (uavsim::core). Kept only until sim/run.cpp includes the new header.
#pragma once

#include "sim/core/rain_attenuation.h"

namespace uavsim::channel {

using core::Polarization;
using core::RainCoefficients;
using core::RainCoefficientsFor;
using core::RainCoefficientsHorizontal;
using core::RainCoefficientsTilted;
using core::RainCoefficientsVertical;
using core::RainSpecificAttenuationDbPerKm;

}  // namespace uavsim::channel
