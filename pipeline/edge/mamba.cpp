#include "pipeline/edge/mamba.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace uavsim::pipeline {
namespace {

void Require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

}  // namespace

void MambaOptions::Validate() const {
  Require(d_model >= 1, "Mamba: d_model (" + std::to_string(d_model) + ") must be >= 1");
  Require(d_state >= 1, "Mamba: d_state (" + std::to_string(d_state) + ") must be >= 1");
  Require(d_conv >= 1, "Mamba: d_conv (" + std::to_string(d_conv) + ") must be >= 1");
  Require(expand >= 1, "Mamba: expand (" + std::to_string(expand) + ") must be >= 1");
  Require(dt_rank >= 0, "Mamba: dt_rank (" + std::to_string(dt_rank) + ") must be >= 0");
  Require(dt_min > 0.0 && dt_max >= dt_min && dt_init_floor > 0.0,
          "Mamba: need 0 < dt_min <= dt_max and dt_init_floor > 0");
}

void MambaRegressorOptions::Validate() const {
  Require(input_dim >= 1,
          "MambaRegressor: input_dim (" + std::to_string(input_dim) + ") must be >= 1");
  Require(output_dim >= 1,
          "MambaRegressor: output_dim (" + std::to_string(output_dim) + ") must be >= 1");
  Require(layers >= 1, "MambaRegressor: layers (" + std::to_string(layers) + ") must be >= 1");
  mamba.Validate();
}

MambaBlockImpl::MambaBlockImpl(const MambaOptions& options) : options_(options) {
  options_.Validate();
  const int64_t d_model = options_.d_model;
  const int64_t d_inner = options_.d_inner();
  const int64_t d_state = options_.d_state;
  const int64_t dt_rank = options_.resolved_dt_rank();

  in_proj = register_module(
      "in_proj", torch::nn::Linear(torch::nn::LinearOptions(d_model, 2 * d_inner).bias(false)));
  conv1d = register_module(
      "conv1d", torch::nn::Conv1d(torch::nn::Conv1dOptions(d_inner, d_inner, options_.d_conv)
                                      .groups(d_inner)
                                      .padding(options_.d_conv - 1)
                                      .bias(true)));
  x_proj = register_module(
      "x_proj",
      torch::nn::Linear(torch::nn::LinearOptions(d_inner, dt_rank + 2 * d_state).bias(false)));
  dt_proj = register_module("dt_proj", torch::nn::Linear(dt_rank, d_inner));
  out_proj = register_module(
      "out_proj", torch::nn::Linear(torch::nn::LinearOptions(d_inner, d_model).bias(false)));

  torch::NoGradGuard no_grad;
  // Keeps the variance of Δ's pre-activation at initialisation.
  const double dt_init_std = 1.0 / std::sqrt(static_cast<double>(dt_rank));
  dt_proj->weight.uniform_(-dt_init_std, dt_init_std);
  const double log_min = std::log(options_.dt_min);
  const double log_max = std::log(options_.dt_max);
  const torch::Tensor dt = torch::exp(torch::rand({d_inner}) * (log_max - log_min) + log_min)
                               .clamp_min(options_.dt_init_floor);
  // Inverse softplus, so softplus(bias) = dt.
  dt_proj->bias.copy_(dt + torch::log(-torch::expm1(-dt)));

  // S4D-real: A = -(1, 2, ..., N) for every channel.
  A_log = register_parameter(
      "A_log",
      torch::log(torch::arange(1, d_state + 1, torch::kFloat32)).repeat({d_inner, 1}).contiguous());
  D = register_parameter("D", torch::ones({d_inner}));
}

MambaState MambaBlockImpl::InitialState(int64_t batch) const {
  const auto options = A_log.options();
  return {torch::zeros({batch, options_.d_inner(), options_.d_conv}, options),
          torch::zeros({batch, options_.d_inner(), options_.d_state}, options)};
}

torch::Tensor MambaBlockImpl::forward(const torch::Tensor& hidden, MambaState* final_state) {
  TORCH_CHECK(hidden.dim() == 3 && hidden.size(2) == options_.d_model,
              "MambaBlock: input must be [B, L, d_model] with d_model = ", options_.d_model,
              ", got ", hidden.sizes());
  const int64_t length = hidden.size(1);
  const int64_t dt_rank = options_.resolved_dt_rank();
  const int64_t d_state = options_.d_state;

  const std::vector<torch::Tensor> xz = in_proj(hidden).transpose(1, 2).chunk(2, /*dim=*/1);
  torch::Tensor x = xz[0];  // [B, d_inner, L]
  const torch::Tensor& z = xz[1];
  if (final_state != nullptr) {
    // The conv's state is its last d_conv inputs, zero-padded on the left
    // for sequences shorter than the kernel (the reference's F.pad).
    const int64_t keep = std::min<int64_t>(length, options_.d_conv);
    final_state->conv =
        torch::cat({torch::zeros({x.size(0), x.size(1), options_.d_conv - keep}, x.options()),
                    x.slice(2, length - keep, length)},
                   /*dim=*/2);
  }
  // Padding d_conv - 1 on both sides; keeping the first L outputs makes it causal.
  x = torch::silu(conv1d(x).slice(2, 0, length));

  const std::vector<torch::Tensor> dbc =
      x_proj(x.transpose(1, 2)).split_with_sizes({dt_rank, d_state, d_state}, /*dim=*/-1);
  // Δ's bias enters in the scan (delta_bias), as in the reference.
  const torch::Tensor delta = torch::matmul(dbc[0], dt_proj->weight.t()).transpose(1, 2);
  const torch::Tensor Bm = dbc[1].transpose(1, 2);  // [B, N, L]
  const torch::Tensor Cm = dbc[2].transpose(1, 2);
  const torch::Tensor A = -torch::exp(A_log);
  const torch::Tensor y = SelectiveScan(x, delta, A, Bm, Cm, D, z, dt_proj->bias,
                                        final_state != nullptr ? &final_state->ssm : nullptr);
  return out_proj(y.transpose(1, 2));
}

torch::Tensor MambaBlockImpl::Step(const torch::Tensor& hidden, MambaState* state) {
  TORCH_CHECK(hidden.dim() == 2 && hidden.size(1) == options_.d_model,
              "MambaBlock::Step: input must be [B, d_model] with d_model = ", options_.d_model,
              ", got ", hidden.sizes());
  TORCH_CHECK(state != nullptr && state->conv.defined() && state->ssm.defined(),
              "MambaBlock::Step: needs a state (InitialState)");
  const int64_t dt_rank = options_.resolved_dt_rank();
  const int64_t d_state = options_.d_state;

  const std::vector<torch::Tensor> xz = in_proj(hidden).chunk(2, /*dim=*/-1);
  // Conv step: shift the window by one and append x (the reference's roll).
  state->conv = torch::cat({state->conv.slice(2, 1), xz[0].unsqueeze(-1)}, /*dim=*/2);
  torch::Tensor x = (state->conv * conv1d->weight.squeeze(1)).sum(-1) + conv1d->bias;
  x = torch::silu(x);

  const std::vector<torch::Tensor> dbc =
      x_proj(x).split_with_sizes({dt_rank, d_state, d_state}, /*dim=*/-1);
  const torch::Tensor dt = torch::softplus(torch::linear(dbc[0], dt_proj->weight) + dt_proj->bias);
  const torch::Tensor A = -torch::exp(A_log);
  // Ā = exp(ΔA), B̄ = ΔB.
  const torch::Tensor dA = torch::exp(dt.unsqueeze(-1) * A);
  const torch::Tensor dB = dt.unsqueeze(-1) * dbc[1].unsqueeze(1);
  state->ssm = state->ssm * dA + x.unsqueeze(-1) * dB;
  torch::Tensor y = (state->ssm * dbc[2].unsqueeze(1)).sum(-1) + D * x;
  y = y * torch::silu(xz[1]);
  return out_proj(y);
}

MambaRegressorImpl::MambaRegressorImpl(const MambaRegressorOptions& options) : options_(options) {
  options_.Validate();
  const int64_t d_model = options_.mamba.d_model;
  embed = register_module("embed", torch::nn::Linear(options_.input_dim, d_model));
  norms = register_module("norms", torch::nn::ModuleList());
  blocks = register_module("blocks", torch::nn::ModuleList());
  for (int l = 0; l < options_.layers; ++l) {
    norms->push_back(torch::nn::LayerNorm(torch::nn::LayerNormOptions({d_model})));
    MambaBlock block(options_.mamba);
    torch::NoGradGuard no_grad;
    block->out_proj->weight.div_(std::sqrt(static_cast<double>(options_.layers)));
    blocks->push_back(block);
  }
  norm_f = register_module("norm_f", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d_model})));
  head = register_module("head", torch::nn::Linear(d_model, options_.output_dim));
}

MambaRegressorState MambaRegressorImpl::InitialState(int64_t batch) const {
  MambaRegressorState state;
  for (const auto& block : *blocks)
    state.layers.push_back(block->as<MambaBlockImpl>()->InitialState(batch));
  return state;
}

torch::Tensor MambaRegressorImpl::forward(const torch::Tensor& x,
                                          MambaRegressorState* final_state) {
  TORCH_CHECK(x.dim() == 3 && x.size(2) == options_.input_dim,
              "MambaRegressor: input must be [B, L, input_dim] with input_dim = ",
              options_.input_dim, ", got ", x.sizes());
  if (final_state != nullptr) final_state->layers.assign(blocks->size(), MambaState{});
  torch::Tensor h = embed(x);
  for (std::size_t l = 0; l < blocks->size(); ++l) {
    const torch::Tensor normed = norms[l]->as<torch::nn::LayerNormImpl>()->forward(h);
    h = h + blocks[l]->as<MambaBlockImpl>()->forward(
                normed, final_state != nullptr ? &final_state->layers[l] : nullptr);
  }
  return head(norm_f(h));
}

torch::Tensor MambaRegressorImpl::Step(const torch::Tensor& x, MambaRegressorState* state) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == options_.input_dim,
              "MambaRegressor::Step: input must be [B, input_dim] with input_dim = ",
              options_.input_dim, ", got ", x.sizes());
  TORCH_CHECK(state != nullptr && state->layers.size() == blocks->size(),
              "MambaRegressor::Step: needs a state (InitialState)");
  torch::Tensor h = embed(x);
  for (std::size_t l = 0; l < blocks->size(); ++l) {
    const torch::Tensor normed = norms[l]->as<torch::nn::LayerNormImpl>()->forward(h);
    h = h + blocks[l]->as<MambaBlockImpl>()->Step(normed, &state->layers[l]);
  }
  return head(norm_f(h));
}

}  // namespace uavsim::pipeline
