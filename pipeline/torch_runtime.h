// LibTorch's process-wide settings, set once before the first LibTorch call:
// a fixed thread count (results and speed must not depend on the machine's
// idle cores) and passive OpenMP waiting (LibTorch's OpenMP threads spin and
// starve Embree's TBB workers or other sweep jobs sharing the cores), and a
// malloc that keeps 1 GB of freed heap instead of returning it to the kernel
// after every step (M_TOP_PAD; LibTorch's tensors of tens of MB otherwise
// fault in fresh pages at every training step: NOTES.md).
#pragma once

#include <cstdint>

namespace uavsim::pipeline {

// Sets intra-op threads (LibTorch's and OpenBLAS's) to `threads` (>= 1) and
// seeds LibTorch's generator.
// Call before any other LibTorch use; later calls only reseed.
void InitTorch(int threads, std::uint64_t seed);

}  // namespace uavsim::pipeline
