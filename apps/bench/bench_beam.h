// `uavsim bench beam`: downlink beam evaluations per second (channel/).
#pragma once

#include <ostream>

namespace uavsim::sim {

// One beam evaluation = the channel at the UAV's true position
// (BeamChannel::RealizeInto: direct path, image-method reflections off the
// listed facades, steering vectors, h) + a beam for a position estimate
// (steered, or the best DFT codeword) + gamma = |h^H f|^2. Rows: 8x8 (the
// default), 16x16 and 32x32 arrays; LOS only, and 8 or 64 facades; steered
// and DFT beams; and whole DownlinkScorer windows (channel once, then the
// perfect, two method and three DFT beams, and the rate at 21 SNR points).
// The UAV flies the default 25 m orbit around the default base station and
// the estimates carry 1 m of noise, from a fixed-seed RngStream: 4096 samples
// along the orbit, evaluated in whole sweeps, so every run evaluates the same
// beams. The world is a closed-form oracle that blocks nothing: the engine's
// Embree queries (1 per direct path, 2 per candidate reflection) come on top
// and are measured by `uavsim bench raycast`.
//
// Google Benchmark times the evaluations (wall clock) for at least 0.5 s per
// row after a warm-up of 0.05 s (both rounded up to whole sweeps). Writes a
// table to `out`: array, paths, beam, evaluations timed, seconds, thousand
// evaluations per second, mean gamma over the timed evaluations (a checksum;
// the scorer rows: over every window scored). With `quiet` only the table.
// Takes several seconds. Returns 0.
int BenchBeam(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
