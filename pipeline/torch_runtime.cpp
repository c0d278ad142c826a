#include "pipeline/torch_runtime.h"

#include <torch/torch.h>

#include <dlfcn.h>
#include <malloc.h>

#include <cstdlib>
#include <mutex>

namespace uavsim::pipeline {
namespace {

constexpr int kMallocTopPad_bytes = 1 << 30;

}  // namespace

void InitTorch(int threads, std::uint64_t seed) {
  static std::once_flag once;
  std::call_once(once, [threads] {
    // glibc trims the heap's free top above 2x its (dynamic) mmap threshold
    // and serves requests the top cannot from fresh pages: a training step's
    // tensors (tens of MB each, ~0.5 GB a step) were returned to the kernel
    // and faulted back in at every step, 2.2 M page faults in a toy
    // training, most of its time. Keeping 1 GB of free top (virtual until
    // touched) serves them from the heap: camera stage 1 ~19x faster,
    // results bit-identical (BENCHMARKS.md). A MALLOC_TOP_PAD_ the user set wins.
    if (!std::getenv("MALLOC_TOP_PAD_")) mallopt(M_TOP_PAD, kMallocTopPad_bytes);
    // Blocks above glibc's mmap threshold (at most 32 MB) bypass the heap:
    // each is a fresh mmap, zero-faulted page by page, and unmapped when
    // freed, at every step. The paper's unpooled camera encoder has 64 MB
    // weights (and gradients, Adam temporaries), and encoding episodes for
    // stage 2 allocates batches of crops: a --quick training spent 2.75 M
    // page faults and two thirds of its wall time there. Serving every
    // block from the heap: 57 -> 20 s (2 epochs a stage), the paper
    // preset's camera epoch 29 -> 12 s, results bit-identical
    // (BENCHMARKS.md). A MALLOC_MMAP_MAX_ the user set wins.
    if (!std::getenv("MALLOC_MMAP_MAX_")) mallopt(M_MMAP_MAX, 0);
    // Must be in the environment before OpenMP starts its pool.
    setenv("OMP_WAIT_POLICY", "PASSIVE", /*overwrite=*/0);
    at::set_num_threads(threads < 1 ? 1 : threads);
    at::set_num_interop_threads(1);
    // LibTorch's setting does not reach OpenBLAS's own pthread pool; without
    // this a "one-thread" encode ran on two. Looked up at run time because
    // the BLAS in use is whatever Debian's alternatives point to.
    using SetThreads = void (*)(int);
    if (auto* set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads")))
      set(threads < 1 ? 1 : threads);
  });
  torch::manual_seed(seed);
}

}  // namespace uavsim::pipeline
