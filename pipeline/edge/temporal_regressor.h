// The temporal regressor over the window sequence of fused features t^f(k)
// (paper Sec. V-C): the paper's Mamba (mamba.h) and the three networks it is
// compared against "assuming that the fusion module is unchanged" (Sec. VI,
// Fig. 11): GRU (Cho et al. 2014; the paper cites [dey2017gate]), LSTM
// ([hochreiter1997long]) and TCN ([lea2017temporal], in the residual form of
// Bai et al. 2018).
//
// Every kind has the Mamba regressor's front and back: embed (Linear
// input_dim -> width), the temporal core, a final LayerNorm and the linear
// head (Linear width -> output_dim). Every kind's contract:
//   forward: x [B, L, input_dim] -> [B, L, output_dim], from a zero state;
//     causal (output l depends on inputs 0..l only). If final_state is given
//     it receives the state after the last step, from which Step continues.
//   Step: x [B, input_dim] -> [B, output_dim]; advances *state. Stepping a
//     sequence from InitialState(B) agrees with forward to float rounding.
//   InitialState(B): zeros, on the parameters' dtype.
// Wrong shapes or a missing state throw c10::Error; bad options
// std::invalid_argument naming the field. Weights are drawn from LibTorch's
// global generator at construction, for the chosen kind only (a Mamba draws
// what MambaRegressor always drew): seed it for reproducible weights.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <variant>
#include <vector>

#include "pipeline/edge/mamba.h"
#include "pipeline/edge/temporal_kind.h"

namespace uavsim::pipeline {

// GRU or LSTM: `layers` stacked cells (torch::nn::GRU / LSTM, LibTorch's
// initialisation), every hidden state `width` wide.
struct RecurrentRegressorOptions {
  int input_dim = 48;
  int output_dim = 3;
  int width = 64;  // embed's output and every layer's hidden size
  int layers = 2;
  void Validate() const;  // Throws std::invalid_argument naming the field.
};

// h (and, LSTM only, the cell c) of every layer: [layers, B, width].
struct RecurrentState {
  torch::Tensor h;
  torch::Tensor c;  // undefined for a GRU
};

class RecurrentRegressorImpl : public torch::nn::Module {
 public:
  // kind: kGru or kLstm (else std::invalid_argument).
  RecurrentRegressorImpl(TemporalKind kind, const RecurrentRegressorOptions& options);

  torch::Tensor forward(const torch::Tensor& x, RecurrentState* final_state = nullptr);
  torch::Tensor Step(const torch::Tensor& x, RecurrentState* state);
  RecurrentState InitialState(int64_t batch) const;
  TemporalKind kind() const { return kind_; }
  const RecurrentRegressorOptions& options() const { return options_; }

  torch::nn::Linear embed{nullptr};
  torch::nn::GRU gru{nullptr};    // kGru only
  torch::nn::LSTM lstm{nullptr};  // kLstm only
  torch::nn::LayerNorm norm_f{nullptr};
  torch::nn::Linear head{nullptr};

 private:
  // x [B, L, input_dim] from *state, which it advances.
  torch::Tensor Run(const torch::Tensor& x, RecurrentState* state);

  TemporalKind kind_;
  RecurrentRegressorOptions options_;
};
TORCH_MODULE(RecurrentRegressor);

// TCN: `layers` residual blocks (Bai et al. 2018, Fig. 1b, without weight
// norm and dropout), block i = 0, 1, ... dilated by 2^i:
//   out = ReLU(h + ReLU(conv2(ReLU(conv1(h))))),
// each conv causal (left zero-padded by (kernel - 1) 2^i), width -> width.
// Conv weights ~ N(0, 0.01) as Bai et al., biases LibTorch's default.
struct TcnRegressorOptions {
  int input_dim = 48;
  int output_dim = 3;
  int width = 64;
  int layers = 2;  // residual blocks
  int kernel = 3;
  // Windows an output sees: 1 + 2 (kernel - 1)(2^layers - 1).
  int64_t receptive_field() const;
  void Validate() const;  // Throws std::invalid_argument naming the field.
};

// Each conv's last (kernel - 1) dilation inputs [B, width, (kernel - 1)
// dilation], newest last, two per block (conv1, conv2) in block order.
struct TcnState {
  std::vector<torch::Tensor> inputs;
};

class TcnBlockImpl : public torch::nn::Module {
 public:
  TcnBlockImpl(int width, int kernel, int dilation);
  // h: [B, width, L] -> [B, width, L], from zero states; final_conv1/2 (if
  // given) receive the two convs' states after the last step.
  torch::Tensor forward(const torch::Tensor& h, torch::Tensor* final_conv1 = nullptr,
                        torch::Tensor* final_conv2 = nullptr);
  // h: [B, width]; advances both convs' states.
  torch::Tensor Step(const torch::Tensor& h, torch::Tensor* conv1_state,
                     torch::Tensor* conv2_state);
  int history() const { return (kernel_ - 1) * dilation_; }  // inputs a conv keeps

  torch::nn::Conv1d conv1{nullptr};
  torch::nn::Conv1d conv2{nullptr};

 private:
  int kernel_;
  int dilation_;
};
TORCH_MODULE(TcnBlock);

class TcnRegressorImpl : public torch::nn::Module {
 public:
  explicit TcnRegressorImpl(const TcnRegressorOptions& options);

  torch::Tensor forward(const torch::Tensor& x, TcnState* final_state = nullptr);
  torch::Tensor Step(const torch::Tensor& x, TcnState* state);
  TcnState InitialState(int64_t batch) const;
  const TcnRegressorOptions& options() const { return options_; }

  torch::nn::Linear embed{nullptr};
  torch::nn::ModuleList blocks{nullptr};  // TcnBlock per layer
  torch::nn::LayerNorm norm_f{nullptr};
  torch::nn::Linear head{nullptr};

 private:
  TcnRegressorOptions options_;
};
TORCH_MODULE(TcnRegressor);

// Which kind, and each kind's sizes (only the chosen kind's are used).
//
// Parameter-matched sizes (MatchedTemporalOptions): at the default
// configuration (input 48 = 3 modalities x z 16, output 3, 2 layers; Mamba
// d_model 64, d_state 16, d_conv 4, expand 2) the counts are
//   Mamba          68 995
//   GRU  width 73  68 769  (-0.3 %)
//   LSTM width 64  70 019  (+1.5 %)
//   TCN  width 73, kernel 3 (receptive field 13 windows)  68 185  (-1.2 %)
// (ParameterCount; the test counts the modules' tensors).
struct TemporalRegressorOptions {
  TemporalKind kind = TemporalKind::kMamba;
  MambaRegressorOptions mamba;          // kMamba
  RecurrentRegressorOptions recurrent;  // kGru, kLstm
  TcnRegressorOptions tcn;              // kTcn
  int input_dim() const;
  int output_dim() const;
  void Validate() const;  // the chosen kind's
};

// Trainable parameters (numel) of a regressor with these options.
int64_t ParameterCount(const MambaRegressorOptions& o);
int64_t ParameterCount(TemporalKind kind, const RecurrentRegressorOptions& o);  // kGru, kLstm
int64_t ParameterCount(const TcnRegressorOptions& o);
int64_t ParameterCount(const TemporalRegressorOptions& o);

// `kind` with the Mamba's input, output and layers, and the width whose
// ParameterCount is nearest the Mamba's (ties: the narrower); kMamba:
// `mamba` itself. Throws std::invalid_argument for invalid options.
TemporalRegressorOptions MatchedTemporalOptions(TemporalKind kind,
                                                const MambaRegressorOptions& mamba,
                                                int tcn_kernel = 3);

using TemporalState = std::variant<MambaRegressorState, RecurrentState, TcnState>;

// The one regressor module of UavLocModel: owns the chosen kind and
// registers that kind's submodules as its own, so a Mamba's parameters keep
// MambaRegressor's names (embed, norms, blocks, norm_f, head) and models
// saved before this wrapper load unchanged.
class TemporalRegressorImpl : public torch::nn::Module {
 public:
  explicit TemporalRegressorImpl(const TemporalRegressorOptions& options);

  torch::Tensor forward(const torch::Tensor& x, TemporalState* final_state = nullptr);
  // Throws c10::Error unless *state holds this kind's state.
  torch::Tensor Step(const torch::Tensor& x, TemporalState* state);
  TemporalState InitialState(int64_t batch) const;
  TemporalKind kind() const { return options_.kind; }
  const TemporalRegressorOptions& options() const { return options_; }
  // Also sets the chosen kind's own flag (its submodules are ours).
  void train(bool on = true) override;

  // Every kind's front and back.
  torch::nn::Linear embed{nullptr};
  torch::nn::LayerNorm norm_f{nullptr};
  torch::nn::Linear head{nullptr};
  // The chosen kind (the others stay null).
  MambaRegressor mamba{nullptr};
  RecurrentRegressor recurrent{nullptr};
  TcnRegressor tcn{nullptr};

 private:
  TemporalRegressorOptions options_;
  std::shared_ptr<torch::nn::Module> chosen_;
};
TORCH_MODULE(TemporalRegressor);

}  // namespace uavsim::pipeline
