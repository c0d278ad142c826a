// The selective scan of the Mamba block (paper Sec. V-C, Eq. (27);
// selective_scan_ref of state-spaces/mamba with variable B and C), from a
// zero state:
//   Δ = softplus(delta + delta_bias), h_l = exp(Δ_l A) h_{l-1} + Δ_l B_l u_l,
//   y_l = C_l h_l + D u_l, out = y · SiLU(z).
// Shapes: u, delta, z: [B, D, L]; A: [D, N]; Bm, Cm: [B, N, L]; D_skip,
// delta_bias: [D]. Returns [B, D, L]; writes h_L ([B, D, N], zeros for
// L = 0) to *last_state if given. softplus is LibTorch's (beta 1, linear
// above 20).
#pragma once

#include <torch/torch.h>

namespace uavsim::pipeline {

// One autograd node for the whole scan: the forward runs the recurrence in
// plain loops, the backward is the hand-written reverse-time adjoint (first
// order only: its gradients carry no graph). Gradients flow to every input
// and from both outputs. Used when every tensor is a strided CPU tensor of
// one dtype, float32 or float64; anything else goes to
// SelectiveScanReference. Results do not depend on the intra-op thread count
// (each sequence is scanned by one thread; sums over the batch run in batch
// order). Throws c10::Error for inconsistent shapes.
torch::Tensor SelectiveScan(const torch::Tensor& u, const torch::Tensor& delta,
                            const torch::Tensor& A, const torch::Tensor& Bm,
                            const torch::Tensor& Cm, const torch::Tensor& D_skip,
                            const torch::Tensor& z, const torch::Tensor& delta_bias,
                            torch::Tensor* last_state = nullptr);

// The same function as a loop of LibTorch ops that autograd records step by
// step (the implementation before the fused one): the reference the tests
// compare SelectiveScan's values and gradients against. For L = 0 the
// output and *last_state are zeros without a graph.
torch::Tensor SelectiveScanReference(const torch::Tensor& u, const torch::Tensor& delta,
                                     const torch::Tensor& A, const torch::Tensor& Bm,
                                     const torch::Tensor& Cm, const torch::Tensor& D_skip,
                                     const torch::Tensor& z, const torch::Tensor& delta_bias,
                                     torch::Tensor* last_state = nullptr);

}  // namespace uavsim::pipeline
