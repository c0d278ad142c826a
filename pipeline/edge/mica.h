// MICA, MI-inspired cross-attention (paper Sec. V-B2, Table I): each
// modality m attends to the OTHER available modalities n with weights from a
// learned pairwise dependency score g^m(t^{m,w}, t^{n,w}) instead of a dot
// product, and adds them to its own features through learnable gains λ^{m,n}.
#pragma once

#include <torch/torch.h>

namespace uavsim::pipeline {

struct MicaOutput {
  torch::Tensor fused;      // t^{m,f}(k): [N, M, z]
  torch::Tensor attention;  // α^{m<-n}: [N, M, M], [., m, n]; 0 for n = m and missing n
};

class MicaImpl : public torch::nn::Module {
 public:
  // One score MLP per target modality m (g^m_η of Eq. (24)), on [t^m, t^n].
  MicaImpl(int modalities, int latent_dim, int hidden = 128, double lambda_init = 0.5);

  // weighted: t^{m,w}(k), [N, M, z]; mask: [N, M], 1 available, 0 missing.
  // A missing modality n contributes nothing to any m; a modality with no
  // available partner gets its residual t^{m,w} alone. A missing m still
  // receives its available partners' contributions (the paper's formula is
  // the same for every m; its own residual is already 0 after MADW).
  MicaOutput forward(const torch::Tensor& weighted, const torch::Tensor& mask);

  torch::nn::ModuleList scores;  // M x ScoreMlp(2z, hidden)
  torch::Tensor lambda;          // λ^{m,n}: [M, M], init lambda_init; the diagonal is unused
};
TORCH_MODULE(Mica);

}  // namespace uavsim::pipeline
