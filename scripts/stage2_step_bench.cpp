// Stage-2 training step throughput: forward + backward + Adam of the
// anchored UavLocModel (fusion + Mamba + head) at the trainer's stage-2
// shapes, one LibTorch thread, random inputs. Not part of the build: it is
// compiled by hand against a build's libuavsim_pipeline.a to compare two
// builds side by side (HANDOFF-scan.md has the command).
//   stage2_step_bench [K=30] [batch=16] [steps=40] [only_mamba=0]
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "pipeline/edge/uavloc_model.h"
#include "pipeline/torch_runtime.h"

int main(int argc, char** argv) {
  using namespace uavsim::pipeline;
  const int64_t k = argc > 1 ? std::atoi(argv[1]) : 30;
  const int64_t batch = argc > 2 ? std::atoi(argv[2]) : 16;
  const int steps = argc > 3 ? std::atoi(argv[3]) : 40;
  const bool only_mamba = argc > 4 && std::atoi(argv[4]) != 0;
  InitTorch(1, 7);
  UavLocModelConfig config;
  config.anchored = true;
  UavLocModel model(config);
  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(2e-3));
  const int64_t c = kAnchorCandidates;
  const torch::Tensor latents = torch::randn({batch, k, kModalityCount, config.latent_dim});
  const torch::Tensor mask = (torch::rand({batch, k, kModalityCount}) > 0.2).to(torch::kFloat32);
  AnchorBatch anchors{torch::randn({batch, k, kAnchorFeatures}), torch::randn({batch, k, c, 3}),
                      (torch::rand({batch, k, c}) > 0.5).to(torch::kFloat32),
                      torch::randn({batch, k, 7})};
  anchors.ray.narrow(-1, 0, 1).fill_(1.0);
  const torch::Tensor truth = torch::randn({batch, k, 3});
  const torch::Tensor mamba_in = torch::randn({batch, k, model->regressor->options().input_dim});
  auto step = [&] {
    adam.zero_grad();
    torch::Tensor loss;
    if (only_mamba) {
      loss = model->regressor(mamba_in).square().mean();
    } else {
      torch::Tensor log_w, h;
      model->forward(latents, mask, &anchors, &log_w, &h);
      loss = (log_w.exp() * (h - truth.unsqueeze(-2)).square().sum(-1)).sum(-1).mean();
    }
    loss.backward();
    adam.step();
  };
  for (int i = 0; i < 3; ++i) step();  // warm-up
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) step();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s K %ld batch %ld: %.2f ms/step, %.1f crops/s, %.0f windows/s\n",
              only_mamba ? "mamba only" : "fusion+mamba+head", static_cast<long>(k),
              static_cast<long>(batch), 1e3 * s / steps, steps * batch / s, steps * batch * k / s);
  return 0;
}
