// `uavsim bench noise`: standard normal samples per second, the counter-based
// generator against RngStream::Normal.
#pragma once

#include <ostream>

namespace uavsim::sim {

// Draws the noise of stereo-camera frames (two eyes of 640 x 480) row by row,
// one key per row as sensors/fisheye_stereo.cpp keys its rows, on one thread:
//   RngStream::Normal      a stream per row, one Normal() per pixel (today's camera)
//   CounterNormal::Fill    a generator per row, the row in one call (float, double)
//   CounterNormal::At      a generator per row, one At(u) per pixel
// and writes one table row per case to `out`: case, million samples timed,
// seconds (wall), million samples per second, nanoseconds per sample,
// speed-up over RngStream::Normal. Google Benchmark times whole frames (wall
// clock) for at least 0.1 s after a warm-up of 0.02 s, three repetitions, and
// the fastest is kept (the machine may be shared). The keys are fixed and
// every repetition starts at frame 0, so every run draws the same numbers;
// only the timings vary. Takes a few seconds. With `quiet` only the table is
// written. Returns 0.
int BenchNoise(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
