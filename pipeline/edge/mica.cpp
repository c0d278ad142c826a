#include "pipeline/edge/mica.h"

#include <stdexcept>
#include <string>
#include <vector>

#include "pipeline/edge/madw.h"

namespace uavsim::pipeline {

MicaImpl::MicaImpl(int modalities, int latent_dim, int hidden, double lambda_init) {
  if (modalities < 1 || latent_dim < 1 || hidden < 1)
    throw std::invalid_argument("Mica: modalities (" + std::to_string(modalities) +
                                "), latent_dim (" + std::to_string(latent_dim) + ") and hidden (" +
                                std::to_string(hidden) + ") must be >= 1");
  scores = register_module("scores", torch::nn::ModuleList());
  for (int m = 0; m < modalities; ++m) scores->push_back(ScoreMlp(2 * latent_dim, hidden));
  lambda = register_parameter("lambda", torch::full({modalities, modalities}, lambda_init));
}

MicaOutput MicaImpl::forward(const torch::Tensor& weighted, const torch::Tensor& mask) {
  const int64_t modalities = static_cast<int64_t>(scores->size());
  TORCH_CHECK(weighted.dim() == 3 && weighted.size(1) == modalities,
              "Mica: features must be [N, M, z] with M = ", modalities, ", got ", weighted.sizes());
  TORCH_CHECK(mask.dim() == 2 && mask.size(0) == weighted.size(0) && mask.size(1) == modalities,
              "Mica: mask must be [N, M], got ", mask.sizes());
  // g^m(t^{m,w}, t^{n,w}) for every partner n at once: [N, M(n)] per m.
  std::vector<torch::Tensor> g;
  g.reserve(static_cast<std::size_t>(modalities));
  for (int64_t m = 0; m < modalities; ++m) {
    const torch::Tensor query = weighted.select(1, m).unsqueeze(1).expand_as(weighted);
    g.push_back(scores[static_cast<std::size_t>(m)]
                    ->as<torch::nn::Sequential>()
                    ->forward(torch::cat({query, weighted}, /*dim=*/-1))
                    .squeeze(-1));
  }
  // Eq. (24): α^{m<-n} = softmax over the other available partners n != m.
  const torch::Tensor others =
      1.0 - torch::eye(modalities, torch::TensorOptions().dtype(weighted.dtype()));
  const torch::Tensor partners = mask.to(weighted.dtype()).unsqueeze(1) * others.unsqueeze(0);
  const torch::Tensor attention = MaskedSoftmax(torch::stack(g, /*dim=*/1), partners, /*dim=*/2);
  // Eq. (25): t^{m,f} = t^{m,w} + sum_n λ^{m,n} α^{m<-n} t^{n,w}.
  const torch::Tensor fused = weighted + torch::bmm(attention * lambda.unsqueeze(0), weighted);
  return {fused, attention};
}

}  // namespace uavsim::pipeline
