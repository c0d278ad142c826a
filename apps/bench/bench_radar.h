// `uavsim bench radar`: time per FMCW radar frame in the default city.
#pragma once

#include <ostream>

namespace uavsim::sim {

// The default scenario's radar at t = 10 s: scatterers from Embree, the IF
// cube, and the node's processing (FFTs, clutter removal, CFAR, angles), one
// thread, dry and in 25 mm/h rain. Writes a table to `out`; returns 0.
int BenchRadar(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
