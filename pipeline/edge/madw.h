// MADW, mask-aware dynamic weighting (paper Sec. V-B1, Table I): a learned
// reliability score per modality, a softmax over the modalities available in
// the window, and the modality's pooled latent scaled by its weight.
#pragma once

#include <torch/torch.h>

namespace uavsim::pipeline {

// Table I's MLP_128 for a scalar score: Linear(in, hidden) -> ReLU ->
// Linear(hidden, 1). Input [..., in], output [..., 1].
torch::nn::Sequential ScoreMlp(int in_features, int hidden);

// softmax[mask · s + (1 - mask) · (-inf)] along `dim`. `scores` and `mask`
// have the same shape; mask is 1 (available) or 0 (missing), any dtype. A
// missing entry gets exactly 0; where no entry along `dim` is available the
// weights are all 0 (not NaN), and no NaN reaches the gradient either.
torch::Tensor MaskedSoftmax(const torch::Tensor& scores, const torch::Tensor& mask, int64_t dim);

struct MadwOutput {
  torch::Tensor weighted;  // t^{m,w}(k): [N, M, z]
  torch::Tensor weights;   // w^m(k): [N, M]; 0 for missing modalities
};

class MadwImpl : public torch::nn::Module {
 public:
  // One score MLP per modality: score^m of Eq. (21) is modality-specific.
  MadwImpl(int modalities, int latent_dim, int hidden = 128);

  // latents: t^{m,e}(k), [N, M, z] (float); mask: [N, M], 1 available, 0
  // missing. N is any flattening of batch and windows.
  MadwOutput forward(const torch::Tensor& latents, const torch::Tensor& mask);

  torch::nn::ModuleList scores;  // M x ScoreMlp(z, hidden)
};
TORCH_MODULE(Madw);

}  // namespace uavsim::pipeline
