#include "pipeline/edge/madw.h"

#include <limits>
#include <stdexcept>
#include <string>

namespace uavsim::pipeline {

torch::nn::Sequential ScoreMlp(int in_features, int hidden) {
  return torch::nn::Sequential(torch::nn::Linear(in_features, hidden), torch::nn::ReLU(),
                               torch::nn::Linear(hidden, 1));
}

torch::Tensor MaskedSoftmax(const torch::Tensor& scores, const torch::Tensor& mask, int64_t dim) {
  const torch::Tensor available = mask > 0.5;
  const torch::Tensor any = available.any(dim, /*keepdim=*/true);
  // -inf where missing makes exp() exactly 0. A row with nothing available
  // would be softmax(-inf, ..., -inf) = NaN, so it is fed zeros instead and
  // its (uniform) result masked away below; the masked entries of the other
  // rows already carry zero gradient through masked_fill.
  torch::Tensor masked =
      scores.masked_fill(available.logical_not(), -std::numeric_limits<float>::infinity());
  masked = torch::where(any, masked, torch::zeros_like(masked));
  return torch::softmax(masked, dim) * available.to(scores.dtype());
}

MadwImpl::MadwImpl(int modalities, int latent_dim, int hidden) {
  if (modalities < 1 || latent_dim < 1 || hidden < 1)
    throw std::invalid_argument("Madw: modalities (" + std::to_string(modalities) +
                                "), latent_dim (" + std::to_string(latent_dim) + ") and hidden (" +
                                std::to_string(hidden) + ") must be >= 1");
  scores = register_module("scores", torch::nn::ModuleList());
  for (int m = 0; m < modalities; ++m) scores->push_back(ScoreMlp(latent_dim, hidden));
}

MadwOutput MadwImpl::forward(const torch::Tensor& latents, const torch::Tensor& mask) {
  const int64_t modalities = static_cast<int64_t>(scores->size());
  TORCH_CHECK(latents.dim() == 3 && latents.size(1) == modalities,
              "Madw: latents must be [N, M, z] with M = ", modalities, ", got ", latents.sizes());
  TORCH_CHECK(mask.dim() == 2 && mask.size(0) == latents.size(0) && mask.size(1) == modalities,
              "Madw: mask must be [N, M], got ", mask.sizes());
  // Eq. (21): s^m(k) = score^m(t^{m,e}(k)).
  std::vector<torch::Tensor> s;
  s.reserve(static_cast<std::size_t>(modalities));
  for (int64_t m = 0; m < modalities; ++m)
    s.push_back(scores[static_cast<std::size_t>(m)]->as<torch::nn::Sequential>()->forward(
        latents.select(1, m)));
  // Eq. (22): w^m(k) = softmax[mask · s + (1 - mask) · (-inf)].
  const torch::Tensor weights = MaskedSoftmax(torch::cat(s, /*dim=*/1), mask, /*dim=*/1);
  // Eq. (23): t^{m,w}(k) = w^m(k) · t^{m,e}(k).
  return {latents * weights.unsqueeze(-1), weights};
}

}  // namespace uavsim::pipeline
