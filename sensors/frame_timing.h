// When a sensor captures: its frame rate, a phase offset of its first frame,
// and the std of its clock's per-frame timing error.
#pragma once

namespace uavsim::sensors {

struct FrameTiming {
  double rate_hz = 10.0;
  double phase_s = 0.0;
  double clock_jitter_s = 0.0;
};

// Writes the timing keys into the enclosing sensor object (not nested).
template <class V>
void VisitTiming(V& v, FrameTiming& c);

}  // namespace uavsim::sensors
