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
// the estimates carry 1 m of noise, from a fixed-seed RngStream, so every run
// evaluates the same beams. The world is a closed-form oracle that blocks
// nothing: the engine's Embree queries (1 per direct path, 2 per candidate
// reflection) come on top and are measured by `uavsim bench raycast`.
//
// Wall time by std::chrono::steady_clock over the timed loop only, after an
// untimed warm-up of a tenth of the evaluations. Writes a table to `out`:
// array, paths, beam, evaluations, seconds, thousand evaluations per second,
// mean gamma (a checksum: it also keeps the work from being optimised away).
// With `quiet` only the table. Takes a few seconds. Returns 0.
int BenchBeam(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
