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
// and writes one table row per case to `out`: case, messages, fragments,
// percentage of messages lost, seconds, thousand messages per second, million
// fragments per second. With `quiet` only the table is written.
//
// Wall time is measured with std::chrono::steady_clock over the event loop
// after an untimed warm-up of a tenth of the messages. The link draws from a
// fixed-seed RngStream, so every run sends, loses and delivers the same
// packets; only the timings vary. Takes a few seconds. Returns 0.
int BenchLink(bool quiet, std::ostream& out);

}  // namespace uavsim::sim
