// Mamba (paper Sec. V-C, Eq. (27)): the block against a naive recurrence
// written here with plain loops from the reference's equations, the
// recurrent step against the full-sequence scan, and shapes.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "pipeline/edge/mamba.h"
#include "pipeline/torch_runtime.h"

namespace uavsim::pipeline {
namespace {

using Matrix = std::vector<std::vector<double>>;

Matrix ToMatrix(const torch::Tensor& t) {  // 2-D
  const torch::Tensor c = t.to(torch::kFloat64).contiguous();
  Matrix m(static_cast<std::size_t>(c.size(0)),
           std::vector<double>(static_cast<std::size_t>(c.size(1))));
  for (std::size_t i = 0; i < m.size(); ++i)
    for (std::size_t j = 0; j < m[i].size(); ++j)
      m[i][j] = c[static_cast<int64_t>(i)][static_cast<int64_t>(j)].item<double>();
  return m;
}

std::vector<double> ToVector(const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat64).contiguous().flatten();
  return std::vector<double>(c.data_ptr<double>(), c.data_ptr<double>() + c.numel());
}

double Silu(double x) { return x / (1.0 + std::exp(-x)); }
double Softplus(double x) { return x > 20.0 ? x : std::log1p(std::exp(x)); }

// Mamba (Gu & Dao 2023, Alg. 2; the reference's step()) one sample at a
// time, in double: input [L][d_model] -> output [L][d_model].
Matrix NaiveMamba(MambaBlockImpl& block, const Matrix& input) {
  const MambaOptions& o = block.options();
  const std::size_t d_inner = static_cast<std::size_t>(o.d_inner());
  const std::size_t n_state = static_cast<std::size_t>(o.d_state);
  const std::size_t rank = static_cast<std::size_t>(o.resolved_dt_rank());
  const std::size_t width = static_cast<std::size_t>(o.d_conv);
  const Matrix w_in = ToMatrix(block.in_proj->weight);
  const Matrix w_conv = ToMatrix(block.conv1d->weight.squeeze(1));
  const std::vector<double> b_conv = ToVector(block.conv1d->bias);
  const Matrix w_x = ToMatrix(block.x_proj->weight);
  const Matrix w_dt = ToMatrix(block.dt_proj->weight);
  const std::vector<double> b_dt = ToVector(block.dt_proj->bias);
  const Matrix a_log = ToMatrix(block.A_log);
  const std::vector<double> d_skip = ToVector(block.D);
  const Matrix w_out = ToMatrix(block.out_proj->weight);

  Matrix x_history;  // in_proj's x of every step, for the causal conv
  Matrix h(d_inner, std::vector<double>(n_state, 0.0));
  Matrix output;
  for (const std::vector<double>& u : input) {
    std::vector<double> x(d_inner), gate(d_inner);
    for (std::size_t c = 0; c < d_inner; ++c) {
      double sx = 0.0, sz = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i) {
        sx += w_in[c][i] * u[i];
        sz += w_in[d_inner + c][i] * u[i];
      }
      x[c] = sx;
      gate[c] = sz;
    }
    x_history.push_back(x);
    const std::size_t t = x_history.size() - 1;
    std::vector<double> xc(d_inner);
    for (std::size_t c = 0; c < d_inner; ++c) {
      double s = b_conv[c];
      for (std::size_t k = 0; k < width; ++k) {
        // Tap k sees the input k - (width - 1) steps back; before t = 0: zero.
        const long back = static_cast<long>(width - 1 - k);
        if (static_cast<long>(t) - back >= 0)
          s += w_conv[c][k] * x_history[t - static_cast<std::size_t>(back)][c];
      }
      xc[c] = Silu(s);
    }
    std::vector<double> proj(w_x.size(), 0.0);
    for (std::size_t j = 0; j < w_x.size(); ++j)
      for (std::size_t c = 0; c < d_inner; ++c) proj[j] += w_x[j][c] * xc[c];
    std::vector<double> y(d_inner);
    for (std::size_t c = 0; c < d_inner; ++c) {
      double pre = b_dt[c];
      for (std::size_t q = 0; q < rank; ++q) pre += w_dt[c][q] * proj[q];
      const double delta = Softplus(pre);
      double yc = 0.0;
      for (std::size_t n = 0; n < n_state; ++n) {
        const double a = -std::exp(a_log[c][n]);
        const double b = proj[rank + n];
        const double cn = proj[rank + n_state + n];
        h[c][n] = std::exp(delta * a) * h[c][n] + delta * b * xc[c];
        yc += cn * h[c][n];
      }
      y[c] = (yc + d_skip[c] * xc[c]) * Silu(gate[c]);
    }
    std::vector<double> out(w_out.size(), 0.0);
    for (std::size_t o2 = 0; o2 < w_out.size(); ++o2)
      for (std::size_t c = 0; c < d_inner; ++c) out[o2] += w_out[o2][c] * y[c];
    output.push_back(out);
  }
  return output;
}

// Moves every parameter off its structured initial value, so the test does
// not pass by the luck of A_log = log(1..N) or D = 1.
void Perturb(torch::nn::Module& module) {
  torch::NoGradGuard no_grad;
  for (auto& p : module.parameters()) p.add_(torch::randn_like(p) * 0.1);
}

}  // namespace

TEST_CASE("MambaBlock: shapes and reference initialisation", "[pipeline]") {
  InitTorch(1, 11);
  MambaOptions o;
  o.d_model = 48;
  MambaBlock block(o);
  const int64_t d_inner = 96, rank = 3, n = 16;
  CHECK(block->in_proj->weight.sizes() == torch::IntArrayRef({2 * d_inner, 48}));
  CHECK(!block->in_proj->bias.defined());
  CHECK(block->conv1d->weight.sizes() == torch::IntArrayRef({d_inner, 1, 4}));
  CHECK(block->x_proj->weight.sizes() == torch::IntArrayRef({rank + 2 * n, d_inner}));
  CHECK(block->dt_proj->weight.sizes() == torch::IntArrayRef({d_inner, rank}));
  CHECK(block->out_proj->weight.sizes() == torch::IntArrayRef({48, d_inner}));
  REQUIRE(block->A_log.sizes() == torch::IntArrayRef({d_inner, n}));
  for (int64_t j = 0; j < n; ++j)
    CHECK(block->A_log[5][j].item<float>() == Approx(std::log(static_cast<double>(j + 1))));
  CHECK(torch::all(block->D == 1.0).item<bool>());
  const torch::Tensor dt = torch::softplus(block->dt_proj->bias);
  CHECK(dt.min().item<float>() >= 1e-3f * 0.999f);
  CHECK(dt.max().item<float>() <= 0.1f * 1.001f);
  CHECK(block->forward(torch::randn({2, 7, 48})).sizes() == torch::IntArrayRef({2, 7, 48}));
}

TEST_CASE("MambaBlock: the scan equals a naive recurrence with plain loops", "[pipeline]") {
  InitTorch(1, 12);
  MambaOptions o;
  o.d_model = 8;
  o.d_state = 5;
  o.expand = 2;
  o.dt_rank = 2;
  MambaBlock block(o);
  Perturb(*block);
  const int64_t length = 23;
  const torch::Tensor input = torch::randn({2, length, 8});
  const torch::Tensor out = block->forward(input);
  for (int64_t b = 0; b < 2; ++b) {
    const Matrix expected = NaiveMamba(*block, ToMatrix(input[b]));
    for (int64_t t = 0; t < length; ++t)
      for (int64_t j = 0; j < 8; ++j)
        CHECK(out[b][t][j].item<double>() ==
              Approx(expected[static_cast<std::size_t>(t)][static_cast<std::size_t>(j)])
                  .margin(1e-5));
  }
}

TEST_CASE("MambaBlock: the recurrent step equals the full-sequence scan", "[pipeline]") {
  InitTorch(1, 13);
  MambaOptions o;
  o.d_model = 32;
  MambaBlock block(o);
  Perturb(*block);
  const int64_t length = 64;
  const torch::Tensor input = torch::randn({3, length, 32});
  torch::NoGradGuard no_grad;
  MambaState scan_state;
  const torch::Tensor scan = block->forward(input, &scan_state);
  MambaState state = block->InitialState(3);
  double worst = 0.0;
  for (int64_t t = 0; t < length; ++t) {
    const torch::Tensor step = block->Step(input.select(1, t), &state);
    worst = std::max(worst, (step - scan.select(1, t)).abs().max().item<double>());
  }
  CHECK(worst < 1e-5);
  CHECK((state.ssm - scan_state.ssm).abs().max().item<double>() < 1e-5);
  CHECK((state.conv - scan_state.conv).abs().max().item<double>() < 1e-6);

  // A scan's final state continues with Step as if the scan had gone on.
  MambaState half;
  block->forward(input.slice(1, 0, 40), &half);
  for (int64_t t = 40; t < length; ++t) {
    const torch::Tensor step = block->Step(input.select(1, t), &half);
    CHECK((step - scan.select(1, t)).abs().max().item<double>() < 1e-5);
  }
  // Shorter than the conv kernel: the state is zero-padded on the left.
  MambaState short_state;
  block->forward(input.slice(1, 0, 2), &short_state);
  CHECK(short_state.conv.select(2, 0).abs().max().item<float>() == 0.0f);
}

TEST_CASE("MambaRegressor: shapes, step equals scan through the layers", "[pipeline]") {
  InitTorch(1, 14);
  MambaRegressorOptions o;
  o.input_dim = 48;
  o.layers = 2;
  o.mamba.d_model = 64;
  MambaRegressor regressor(o);
  Perturb(*regressor);
  const torch::Tensor x = torch::randn({2, 55, 48});
  torch::NoGradGuard no_grad;
  const torch::Tensor scan = regressor(x);
  CHECK(scan.sizes() == torch::IntArrayRef({2, 55, 3}));
  MambaRegressorState state = regressor->InitialState(2);
  REQUIRE(state.layers.size() == 2);
  double worst = 0.0;
  for (int64_t t = 0; t < 55; ++t)
    worst = std::max(
        worst,
        (regressor->Step(x.select(1, t), &state) - scan.select(1, t)).abs().max().item<double>());
  CHECK(worst < 1e-5);
}

}  // namespace uavsim::pipeline
