// `uavsim bench radar`: time per FMCW radar frame in the default city.
#pragma once

#include <ostream>

namespace uavsim::sim {

// The default scenario's radar at t = 10 s: scatterers from Embree (with the
// static cache and without), the IF cube, and the node's processing (FFTs,
// clutter removal, CFAR, angles), one thread, dry and in 25 mm/h rain.
// Google Benchmark times each step (wall clock) for at least 0.5 s. Writes a
// table to `out`: weather, scatterers, wall ms per call of each step, and
// frames per second (1000 / (find + synth + process ms)); unless `quiet`, a
// description line first. The noise comes from a fixed-seed RngStream.
// Returns 0.
int BenchRadar(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
