#include "pipeline/torch_runtime.h"

#include <torch/torch.h>

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
  });
  torch::manual_seed(seed);
}

}  // namespace uavsim::pipeline
