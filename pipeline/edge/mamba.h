// The Mamba temporal regressor (paper Sec. V-C): a selective state-space
// model (Gu & Dao 2023) over the window sequence of fused features, then a
// linear head to a 3-D position.
//
// MambaBlock follows the reference implementation (state-spaces/mamba,
// mamba_simple.py `Mamba.forward` / `Mamba.step` and `selective_scan_ref`):
// in_proj to x and gate z, causal depthwise Conv1d + SiLU, x_proj to (Δ, B,
// C) with Δ = softplus(dt_proj(·)), A = -exp(A_log), D skip, y · SiLU(z),
// out_proj; discretisation Ā = exp(ΔA), B̄x = ΔBx. The block runs a whole
// sequence (training) or one step at a time with explicit state (online); the
// two agree to float rounding.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "pipeline/edge/selective_scan.h"  // SelectiveScan, the block's recurrence

namespace uavsim::pipeline {

struct MambaOptions {
  int d_model = 64;
  int d_state = 16;  // N
  int d_conv = 4;
  int expand = 2;   // d_inner = expand * d_model
  int dt_rank = 0;  // 0: the reference's "auto", ceil(d_model / 16)
  // Initial Δ = softplus(dt bias) is log-uniform in [dt_min, dt_max].
  double dt_min = 1e-3;
  double dt_max = 0.1;
  double dt_init_floor = 1e-4;

  int d_inner() const { return expand * d_model; }
  int resolved_dt_rank() const { return dt_rank > 0 ? dt_rank : (d_model + 15) / 16; }
  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

// The recurrent state of one MambaBlock (zeros at the start of a sequence).
struct MambaState {
  torch::Tensor conv;  // [B, d_inner, d_conv]: the conv's last d_conv inputs, newest last
  torch::Tensor ssm;   // [B, d_inner, d_state]: h(k) of Eq. (27)
};

class MambaBlockImpl : public torch::nn::Module {
 public:
  // Validates `options`; initialises as the reference (S4D-real A_log =
  // log(1..N), D = 1, dt_proj weight U(±dt_rank^-1/2) and bias the inverse
  // softplus of the initial Δ, LibTorch defaults elsewhere). Draws from
  // LibTorch's global generator: seed it for reproducible weights.
  explicit MambaBlockImpl(const MambaOptions& options);

  // hidden: [B, L, d_model] -> [B, L, d_model], from a zero state. If
  // final_state is given it receives the state after the last step, from
  // which Step continues the sequence.
  torch::Tensor forward(const torch::Tensor& hidden, MambaState* final_state = nullptr);

  // One step: hidden [B, d_model] -> [B, d_model]; advances *state.
  torch::Tensor Step(const torch::Tensor& hidden, MambaState* state);

  MambaState InitialState(int64_t batch) const;  // zeros, on the parameters' dtype
  const MambaOptions& options() const { return options_; }

  torch::nn::Linear in_proj{nullptr};   // d_model -> 2 d_inner (x, z), no bias
  torch::nn::Conv1d conv1d{nullptr};    // depthwise, kernel d_conv, causal
  torch::nn::Linear x_proj{nullptr};    // d_inner -> dt_rank + 2 N (Δ, B, C), no bias
  torch::nn::Linear dt_proj{nullptr};   // dt_rank -> d_inner, bias
  torch::nn::Linear out_proj{nullptr};  // d_inner -> d_model, no bias
  torch::Tensor A_log;                  // [d_inner, N]
  torch::Tensor D;                      // [d_inner]

 private:
  MambaOptions options_;
};
TORCH_MODULE(MambaBlock);

struct MambaRegressorOptions {
  int input_dim = 48;  // the fused feature size, M · z
  int output_dim = 3;  // a 3-D position
  int layers = 2;
  MambaOptions mamba;  // mamba.d_model is the residual stream's width
  void Validate() const;
};

struct MambaRegressorState {
  std::vector<MambaState> layers;
};

// embed (Linear input_dim -> d_model), `layers` pre-norm residual blocks
// h <- h + MambaBlock(LayerNorm(h)) as the reference's MixerModel, a final
// LayerNorm, and the linear head (Linear d_model -> output_dim).
class MambaRegressorImpl : public torch::nn::Module {
 public:
  // As MambaBlockImpl; out_proj weights are scaled by 1/sqrt(layers) as the
  // reference's rescale_prenorm_residual does.
  explicit MambaRegressorImpl(const MambaRegressorOptions& options);

  // x: [B, L, input_dim] -> [B, L, output_dim], from a zero state.
  torch::Tensor forward(const torch::Tensor& x, MambaRegressorState* final_state = nullptr);
  // x: [B, input_dim] -> [B, output_dim]; advances *state.
  torch::Tensor Step(const torch::Tensor& x, MambaRegressorState* state);
  MambaRegressorState InitialState(int64_t batch) const;
  const MambaRegressorOptions& options() const { return options_; }

  torch::nn::Linear embed{nullptr};
  torch::nn::ModuleList norms{nullptr};   // LayerNorm(d_model) per layer
  torch::nn::ModuleList blocks{nullptr};  // MambaBlock per layer
  torch::nn::LayerNorm norm_f{nullptr};
  torch::nn::Linear head{nullptr};

 private:
  MambaRegressorOptions options_;
};
TORCH_MODULE(MambaRegressor);

}  // namespace uavsim::pipeline
