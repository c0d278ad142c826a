// Simulated time: signed 64-bit integer nanoseconds, never floating point, so
// a 60 s run at 30 Hz lands on exactly 1800 frames with no drift.
#pragma once

#include <cmath>
#include <cstdint>

namespace uavsim::core {

using SimTime = std::int64_t;  // nanoseconds since the start of the run

constexpr SimTime kNanosecondsPerSecond = 1'000'000'000;
constexpr SimTime kTimeMax = INT64_MAX;

// Rounds to the nearest nanosecond. Callers validate the range beforehand.
inline SimTime Seconds(double s) { return static_cast<SimTime>(std::llround(s * 1e9)); }
inline SimTime Milliseconds(double ms) { return static_cast<SimTime>(std::llround(ms * 1e6)); }
inline double ToSeconds(SimTime t) { return static_cast<double>(t) * 1e-9; }

}  // namespace uavsim::core
