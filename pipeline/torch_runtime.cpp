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
