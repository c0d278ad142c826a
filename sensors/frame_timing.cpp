#include "sensors/frame_timing.h"

#include "core/json_io.h"

namespace uavsim::sensors {

using core::Rule;

template <class V>
void VisitTiming(V& v, FrameTiming& c) {
  v("rate_hz", c.rate_hz, Rule::Positive(10000.0));
  v("phase_s", c.phase_s, Rule::NonNegative(3600.0));
  v("clock_jitter_s", c.clock_jitter_s, Rule::NonNegative(1.0));
  v.Check(c.clock_jitter_s < 0.5 / c.rate_hz, "clock_jitter_s",
          "clock_jitter_s must be below half a frame period (" +
              core::FormatNumber(0.5 / c.rate_hz) + " s)");
}

template void VisitTiming(core::JsonReader&, FrameTiming&);
template void VisitTiming(core::JsonWriter&, FrameTiming&);

}  // namespace uavsim::sensors
