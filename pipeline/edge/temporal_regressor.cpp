#include "pipeline/edge/temporal_regressor.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

namespace uavsim::pipeline {
namespace {

void Require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

void RequireAtLeast(const char* type, const char* field, int value, int minimum) {
  Require(value >= minimum, std::string(type) + ": " + field + " (" + std::to_string(value) +
                                ") must be >= " + std::to_string(minimum));
}

// embed, final LayerNorm and head: what every kind shares.
int64_t FrontAndBack(int64_t input_dim, int64_t width, int64_t output_dim) {
  return (input_dim + 1) * width + 2 * width + (width + 1) * output_dim;
}

}  // namespace

void RecurrentRegressorOptions::Validate() const {
  RequireAtLeast("RecurrentRegressor", "input_dim", input_dim, 1);
  RequireAtLeast("RecurrentRegressor", "output_dim", output_dim, 1);
  RequireAtLeast("RecurrentRegressor", "width", width, 1);
  RequireAtLeast("RecurrentRegressor", "layers", layers, 1);
}

int64_t TcnRegressorOptions::receptive_field() const {
  // Each block's two convs reach (kernel - 1) 2^i windows back each.
  return 1 + 2 * static_cast<int64_t>(kernel - 1) * ((int64_t{1} << layers) - 1);
}

void TcnRegressorOptions::Validate() const {
  RequireAtLeast("TcnRegressor", "input_dim", input_dim, 1);
  RequireAtLeast("TcnRegressor", "output_dim", output_dim, 1);
  RequireAtLeast("TcnRegressor", "width", width, 1);
  RequireAtLeast("TcnRegressor", "layers", layers, 1);
  // 2^(layers - 1) must fit a conv's dilation (int).
  Require(layers <= 24, "TcnRegressor: layers (" + std::to_string(layers) + ") must be <= 24");
  // A kernel of 1 would see no earlier window.
  RequireAtLeast("TcnRegressor", "kernel", kernel, 2);
}

int TemporalRegressorOptions::input_dim() const {
  switch (kind) {
    case TemporalKind::kMamba:
      return mamba.input_dim;
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return recurrent.input_dim;
    case TemporalKind::kTcn:
      return tcn.input_dim;
  }
  return 0;
}

int TemporalRegressorOptions::output_dim() const {
  switch (kind) {
    case TemporalKind::kMamba:
      return mamba.output_dim;
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return recurrent.output_dim;
    case TemporalKind::kTcn:
      return tcn.output_dim;
  }
  return 0;
}

void TemporalRegressorOptions::Validate() const {
  switch (kind) {
    case TemporalKind::kMamba:
      return mamba.Validate();
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return recurrent.Validate();
    case TemporalKind::kTcn:
      return tcn.Validate();
  }
  throw std::invalid_argument("TemporalRegressor: unknown kind");
}

// ---------------------------------------------------------------------------
// Parameter counts (the modules' tensors, as the tests check).

int64_t ParameterCount(const MambaRegressorOptions& o) {
  const int64_t d = o.mamba.d_model, di = o.mamba.d_inner(), n = o.mamba.d_state;
  const int64_t r = o.mamba.resolved_dt_rank(), k = o.mamba.d_conv;
  const int64_t block = 2 * d               // the block's LayerNorm
                        + d * 2 * di        // in_proj
                        + di * k + di       // depthwise conv1d
                        + di * (r + 2 * n)  // x_proj
                        + r * di + di       // dt_proj
                        + di * d            // out_proj
                        + di * n + di;      // A_log, D
  return FrontAndBack(o.input_dim, d, o.output_dim) + o.layers * block;
}

int64_t ParameterCount(TemporalKind kind, const RecurrentRegressorOptions& o) {
  Require(kind == TemporalKind::kGru || kind == TemporalKind::kLstm,
          "ParameterCount: a recurrent regressor is a gru or an lstm");
  const int64_t w = o.width;
  const int64_t gates = kind == TemporalKind::kGru ? 3 : 4;
  // w_ih, w_hh, b_ih, b_hh of each layer (every layer's input is w wide).
  return FrontAndBack(o.input_dim, w, o.output_dim) + o.layers * gates * (2 * w * w + 2 * w);
}

int64_t ParameterCount(const TcnRegressorOptions& o) {
  const int64_t w = o.width;
  return FrontAndBack(o.input_dim, w, o.output_dim) + o.layers * 2 * (w * w * o.kernel + w);
}

int64_t ParameterCount(const TemporalRegressorOptions& o) {
  switch (o.kind) {
    case TemporalKind::kMamba:
      return ParameterCount(o.mamba);
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return ParameterCount(o.kind, o.recurrent);
    case TemporalKind::kTcn:
      return ParameterCount(o.tcn);
  }
  return 0;
}

TemporalRegressorOptions MatchedTemporalOptions(TemporalKind kind,
                                                const MambaRegressorOptions& mamba,
                                                int tcn_kernel) {
  mamba.Validate();
  TemporalRegressorOptions o;
  o.kind = kind;
  o.mamba = mamba;
  o.recurrent.input_dim = o.tcn.input_dim = mamba.input_dim;
  o.recurrent.output_dim = o.tcn.output_dim = mamba.output_dim;
  o.recurrent.layers = o.tcn.layers = mamba.layers;
  o.tcn.kernel = tcn_kernel;
  if (kind == TemporalKind::kMamba) return o;
  const int64_t target = ParameterCount(mamba);
  const auto count = [&](int width) {
    TemporalRegressorOptions c = o;
    c.recurrent.width = c.tcn.width = width;
    return ParameterCount(c);
  };
  // The counts grow with the width: the first width at or above the
  // target, or the one before it if that is nearer.
  int width = 1;
  while (count(width) < target && width < (1 << 20)) ++width;
  if (width > 1 && target - count(width - 1) <= count(width) - target) --width;
  o.recurrent.width = o.tcn.width = width;
  o.Validate();
  return o;
}

// ---------------------------------------------------------------------------
// GRU, LSTM.

RecurrentRegressorImpl::RecurrentRegressorImpl(TemporalKind kind,
                                               const RecurrentRegressorOptions& options)
    : kind_(kind), options_(options) {
  Require(
      kind == TemporalKind::kGru || kind == TemporalKind::kLstm,
      std::string("RecurrentRegressor: kind must be gru or lstm, got ") + TemporalKindName(kind));
  options_.Validate();
  const int64_t w = options_.width;
  embed = register_module("embed", torch::nn::Linear(options_.input_dim, w));
  if (kind_ == TemporalKind::kGru)
    gru = register_module(
        "gru",
        torch::nn::GRU(torch::nn::GRUOptions(w, w).num_layers(options_.layers).batch_first(true)));
  else
    lstm = register_module(
        "lstm", torch::nn::LSTM(
                    torch::nn::LSTMOptions(w, w).num_layers(options_.layers).batch_first(true)));
  norm_f = register_module("norm_f", torch::nn::LayerNorm(torch::nn::LayerNormOptions({w})));
  head = register_module("head", torch::nn::Linear(w, options_.output_dim));
}

RecurrentState RecurrentRegressorImpl::InitialState(int64_t batch) const {
  const auto options = embed->weight.options();
  RecurrentState state;
  state.h = torch::zeros({options_.layers, batch, options_.width}, options);
  if (kind_ == TemporalKind::kLstm)
    state.c = torch::zeros({options_.layers, batch, options_.width}, options);
  return state;
}

torch::Tensor RecurrentRegressorImpl::forward(const torch::Tensor& x, RecurrentState* final_state) {
  TORCH_CHECK(x.dim() == 3 && x.size(2) == options_.input_dim, "RecurrentRegressor (",
              TemporalKindName(kind_),
              "): input must be [B, L, input_dim] with input_dim = ", options_.input_dim, ", got ",
              x.sizes());
  RecurrentState state = InitialState(x.size(0));
  const torch::Tensor out = Run(x, &state);
  if (final_state != nullptr) *final_state = std::move(state);
  return out;
}

torch::Tensor RecurrentRegressorImpl::Step(const torch::Tensor& x, RecurrentState* state) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == options_.input_dim, "RecurrentRegressor::Step (",
              TemporalKindName(kind_),
              "): input must be [B, input_dim] with input_dim = ", options_.input_dim, ", got ",
              x.sizes());
  TORCH_CHECK(
      state != nullptr && state->h.defined() && (kind_ == TemporalKind::kGru || state->c.defined()),
      "RecurrentRegressor::Step: needs a state (InitialState)");
  // A step is a sequence of length 1 to the cells.
  return Run(x.unsqueeze(1), state).squeeze(1);
}

torch::Tensor RecurrentRegressorImpl::Run(const torch::Tensor& x, RecurrentState* state) {
  const torch::Tensor h = embed(x);
  torch::Tensor out;
  if (kind_ == TemporalKind::kGru) {
    std::tie(out, state->h) = gru->forward(h, state->h);
  } else {
    std::tuple<torch::Tensor, torch::Tensor> hc;
    std::tie(out, hc) = lstm->forward(h, std::make_tuple(state->h, state->c));
    std::tie(state->h, state->c) = hc;
  }
  return head(norm_f(out));
}

// ---------------------------------------------------------------------------
// TCN.

TcnBlockImpl::TcnBlockImpl(int width, int kernel, int dilation)
    : kernel_(kernel), dilation_(dilation) {
  const auto conv = [&] {
    return torch::nn::Conv1d(torch::nn::Conv1dOptions(width, width, kernel).dilation(dilation));
  };
  conv1 = register_module("conv1", conv());
  conv2 = register_module("conv2", conv());
  torch::NoGradGuard no_grad;
  // Bai et al. 2018 (their TCN code, init_weights): weights ~ N(0, 0.01).
  conv1->weight.normal_(0.0, 0.01);
  conv2->weight.normal_(0.0, 0.01);
}

torch::Tensor TcnBlockImpl::forward(const torch::Tensor& h, torch::Tensor* final_conv1,
                                    torch::Tensor* final_conv2) {
  const int64_t keep = history();
  // Left zero padding makes the conv causal; the padded input's last `keep`
  // columns are what Step would hold after the sequence.
  const auto causal = [&](torch::nn::Conv1d& conv, const torch::Tensor& in,
                          torch::Tensor* final_state) {
    const torch::Tensor padded = torch::constant_pad_nd(in, {keep, 0});
    if (final_state != nullptr) *final_state = padded.slice(2, in.size(2)).contiguous();
    return conv(padded);
  };
  const torch::Tensor inner = torch::relu(causal(conv1, h, final_conv1));
  // Bai et al. 2018, Fig. 1b: o = Activation(x + F(x)).
  return torch::relu(h + torch::relu(causal(conv2, inner, final_conv2)));
}

torch::Tensor TcnBlockImpl::Step(const torch::Tensor& h, torch::Tensor* conv1_state,
                                 torch::Tensor* conv2_state) {
  // The conv over its kept inputs and the new one gives exactly one output.
  const auto step = [](torch::nn::Conv1d& conv, const torch::Tensor& in, torch::Tensor* state) {
    const torch::Tensor window = torch::cat({*state, in.unsqueeze(2)}, /*dim=*/2);
    *state = window.slice(2, 1);
    return conv(window).squeeze(2);
  };
  const torch::Tensor inner = torch::relu(step(conv1, h, conv1_state));
  return torch::relu(h + torch::relu(step(conv2, inner, conv2_state)));
}

TcnRegressorImpl::TcnRegressorImpl(const TcnRegressorOptions& options) : options_(options) {
  options_.Validate();
  const int64_t w = options_.width;
  embed = register_module("embed", torch::nn::Linear(options_.input_dim, w));
  blocks = register_module("blocks", torch::nn::ModuleList());
  for (int l = 0; l < options_.layers; ++l)
    blocks->push_back(TcnBlock(options_.width, options_.kernel, 1 << l));
  norm_f = register_module("norm_f", torch::nn::LayerNorm(torch::nn::LayerNormOptions({w})));
  head = register_module("head", torch::nn::Linear(w, options_.output_dim));
}

TcnState TcnRegressorImpl::InitialState(int64_t batch) const {
  TcnState state;
  for (const auto& block : *blocks) {
    const int64_t keep = block->as<TcnBlockImpl>()->history();
    for (int conv = 0; conv < 2; ++conv)
      state.inputs.push_back(torch::zeros({batch, options_.width, keep}, embed->weight.options()));
  }
  return state;
}

torch::Tensor TcnRegressorImpl::forward(const torch::Tensor& x, TcnState* final_state) {
  TORCH_CHECK(x.dim() == 3 && x.size(2) == options_.input_dim,
              "TcnRegressor: input must be [B, L, input_dim] with input_dim = ", options_.input_dim,
              ", got ", x.sizes());
  if (final_state != nullptr) final_state->inputs.assign(2 * blocks->size(), torch::Tensor());
  torch::Tensor h = embed(x).transpose(1, 2);  // [B, width, L]
  for (std::size_t l = 0; l < blocks->size(); ++l)
    h = blocks[l]->as<TcnBlockImpl>()->forward(
        h, final_state != nullptr ? &final_state->inputs[2 * l] : nullptr,
        final_state != nullptr ? &final_state->inputs[2 * l + 1] : nullptr);
  return head(norm_f(h.transpose(1, 2)));
}

torch::Tensor TcnRegressorImpl::Step(const torch::Tensor& x, TcnState* state) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == options_.input_dim,
              "TcnRegressor::Step: input must be [B, input_dim] with input_dim = ",
              options_.input_dim, ", got ", x.sizes());
  TORCH_CHECK(state != nullptr && state->inputs.size() == 2 * blocks->size(),
              "TcnRegressor::Step: needs a state (InitialState)");
  torch::Tensor h = embed(x);
  for (std::size_t l = 0; l < blocks->size(); ++l)
    h = blocks[l]->as<TcnBlockImpl>()->Step(h, &state->inputs[2 * l], &state->inputs[2 * l + 1]);
  return head(norm_f(h));
}

// ---------------------------------------------------------------------------
// The wrapper.

TemporalRegressorImpl::TemporalRegressorImpl(const TemporalRegressorOptions& options)
    : options_(options) {
  options_.Validate();
  switch (options_.kind) {
    case TemporalKind::kMamba:
      mamba = MambaRegressor(options_.mamba);
      chosen_ = mamba.ptr();
      embed = mamba->embed, norm_f = mamba->norm_f, head = mamba->head;
      break;
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      recurrent = RecurrentRegressor(options_.kind, options_.recurrent);
      chosen_ = recurrent.ptr();
      embed = recurrent->embed, norm_f = recurrent->norm_f, head = recurrent->head;
      break;
    case TemporalKind::kTcn:
      tcn = TcnRegressor(options_.tcn);
      chosen_ = tcn.ptr();
      embed = tcn->embed, norm_f = tcn->norm_f, head = tcn->head;
      break;
  }
  // The chosen kind's submodules under their own names (no extra level):
  // a Mamba's parameters are named as MambaRegressor's always were.
  for (const auto& child : chosen_->named_children()) register_module(child.key(), child.value());
}

void TemporalRegressorImpl::train(bool on) {
  torch::nn::Module::train(on);
  chosen_->train(on);
}

TemporalState TemporalRegressorImpl::InitialState(int64_t batch) const {
  switch (options_.kind) {
    case TemporalKind::kMamba:
      return mamba->InitialState(batch);
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return recurrent->InitialState(batch);
    case TemporalKind::kTcn:
      return tcn->InitialState(batch);
  }
  return {};
}

torch::Tensor TemporalRegressorImpl::forward(const torch::Tensor& x, TemporalState* final_state) {
  const auto run = [&](auto& regressor, auto state) {
    if (final_state == nullptr) return regressor->forward(x);
    const torch::Tensor y = regressor->forward(x, &state);
    *final_state = std::move(state);
    return y;
  };
  switch (options_.kind) {
    case TemporalKind::kMamba:
      return run(mamba, MambaRegressorState{});
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return run(recurrent, RecurrentState{});
    case TemporalKind::kTcn:
      return run(tcn, TcnState{});
  }
  return {};
}

torch::Tensor TemporalRegressorImpl::Step(const torch::Tensor& x, TemporalState* state) {
  const auto step = [&](auto& regressor, auto* kind_state) {
    TORCH_CHECK(kind_state != nullptr, "TemporalRegressor::Step: the state is not a ",
                TemporalKindName(options_.kind), " regressor's (InitialState)");
    return regressor->Step(x, kind_state);
  };
  TORCH_CHECK(state != nullptr, "TemporalRegressor::Step: needs a state (InitialState)");
  switch (options_.kind) {
    case TemporalKind::kMamba:
      return step(mamba, std::get_if<MambaRegressorState>(state));
    case TemporalKind::kGru:
    case TemporalKind::kLstm:
      return step(recurrent, std::get_if<RecurrentState>(state));
    case TemporalKind::kTcn:
      return step(tcn, std::get_if<TcnState>(state));
  }
  return {};
}

}  // namespace uavsim::pipeline
