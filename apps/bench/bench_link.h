// `uavsim bench link`: throughput of one channel::Uplink under the event core.
#pragma once

#include <ostream>

namespace uavsim::sim {

// One source sends fixed-size messages at a fixed period through one Uplink on
// a core::Simulator; every delivered message is one arrival event. Three cases:
//   latent   80 B messages (an IB latent of 16 floats + header: 1 fragment),
//            100 Mbps at 86 % load, bernoulli loss 1 %, normal jitter
//   frame    64 KiB messages (45 fragments), 1 Gbps at 87 % load,
//            gilbert_elliott loss, 28 GHz link in 10 mm/h of rain
//   overload 1472 B messages (1 fragment) at twice the 20 Mbps line rate into a
//            100-fragment drop-tail buffer: half are dropped
// and writes one table row per case to `out`: case, messages and fragments
// sent in the timed part, percentage of those messages lost, seconds (wall),
// thousand messages per second, million fragments per second. With `quiet`
// only the table is written.
//
// Google Benchmark times the event loop (wall clock) in steps of 1e4 message
// periods for at least 0.1 s per case, after an untimed warm-up of 2e5
// messages (2e4 for the 64 KiB case). The link draws from a fixed-seed
// RngStream, so every run sends, loses and delivers the same sequence of
// packets; only the timings and how many of them the timing takes vary.
// Takes a second or two. Returns 0.
int BenchLink(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
