#include "pipeline/torch_runtime.h"

#include <torch/torch.h>

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>

namespace uavsim::pipeline {

void InitTorch(int threads, std::uint64_t seed) {
  static std::once_flag once;
  std::call_once(once, [threads] {
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
