// MADW and MICA (paper Sec. V-B, Eqs. (21)-(25), Table I): shapes, the
// masked softmax's exact zeros for missing modalities, all-missing windows,
// MICA's softmax over the available partners only and the learnable λ.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>

#include "pipeline/edge/madw.h"
#include "pipeline/edge/mica.h"
#include "pipeline/torch_runtime.h"

namespace uavsim::pipeline {
namespace {

bool AllFinite(const torch::Tensor& t) { return torch::isfinite(t).all().item<bool>(); }

// Every window of the 8 availability patterns of three modalities.
torch::Tensor AllMasks() {
  torch::Tensor mask = torch::zeros({8, 3});
  for (int p = 0; p < 8; ++p)
    for (int m = 0; m < 3; ++m) mask[p][m] = (p >> m) & 1;
  return mask;
}

}  // namespace

TEST_CASE("Madw: Table I shapes, MLP_128 per modality", "[pipeline]") {
  InitTorch(1, 1);
  const int z = 16;
  Madw madw(3, z);
  REQUIRE(madw->scores->size() == 3);
  for (const auto& p : madw->named_parameters()) {
    const auto s = p.value().sizes();
    if (p.key().find(".0.weight") != std::string::npos) CHECK(s == torch::IntArrayRef({128, z}));
    if (p.key().find(".2.weight") != std::string::npos) CHECK(s == torch::IntArrayRef({1, 128}));
  }
  const MadwOutput out = madw(torch::randn({5, 3, z}), torch::ones({5, 3}));
  CHECK(out.weighted.sizes() == torch::IntArrayRef({5, 3, z}));
  CHECK(out.weights.sizes() == torch::IntArrayRef({5, 3}));
}

TEST_CASE("Madw: missing modalities get exactly zero weight, the others sum to 1", "[pipeline]") {
  InitTorch(1, 2);
  Madw madw(3, 8);
  const torch::Tensor mask = AllMasks();
  const torch::Tensor latents = torch::randn({8, 3, 8}) * 10.0;
  const MadwOutput out = madw(latents, mask);
  REQUIRE(AllFinite(out.weights));
  REQUIRE(AllFinite(out.weighted));
  for (int p = 0; p < 8; ++p) {
    double sum = 0.0;
    for (int m = 0; m < 3; ++m) {
      const float w = out.weights[p][m].item<float>();
      if (mask[p][m].item<float>() == 0.0f) {
        CHECK(w == 0.0f);  // exactly
        CHECK(out.weighted[p][m].abs().max().item<float>() == 0.0f);
      } else {
        CHECK(w > 0.0f);
      }
      sum += w;
    }
    CHECK(sum == Approx(p == 0 ? 0.0 : 1.0).margin(1e-6));  // p = 0: all missing
  }
  // Scaling of Eq. (23).
  CHECK(torch::allclose(out.weighted, latents * out.weights.unsqueeze(-1)));
}

TEST_CASE("MaskedSoftmax: matches softmax over the available entries, no NaN in gradients",
          "[pipeline]") {
  InitTorch(1, 3);
  const torch::Tensor scores = torch::randn({8, 3}).requires_grad_(true);
  const torch::Tensor mask = AllMasks();
  const torch::Tensor w = MaskedSoftmax(scores, mask, 1);
  for (int p = 1; p < 8; ++p) {
    double denom = 0.0;
    for (int m = 0; m < 3; ++m)
      if (mask[p][m].item<float>() > 0) denom += std::exp(scores[p][m].item<double>());
    for (int m = 0; m < 3; ++m) {
      const double expected =
          mask[p][m].item<float>() > 0 ? std::exp(scores[p][m].item<double>()) / denom : 0.0;
      CHECK(w[p][m].item<double>() == Approx(expected).margin(1e-6));
    }
  }
  (w * torch::randn({8, 3})).sum().backward();
  CHECK(AllFinite(scores.grad()));
  CHECK(scores.grad()[0].abs().sum().item<float>() == 0.0f);  // all missing: no signal
}

TEST_CASE("Mica: Table I shapes, lambda starts at 0.5 and learns", "[pipeline]") {
  InitTorch(1, 4);
  const int z = 16;
  Mica mica(3, z);
  for (const auto& p : mica->named_parameters()) {
    const auto s = p.value().sizes();
    if (p.key().find(".0.weight") != std::string::npos)
      CHECK(s == torch::IntArrayRef({128, 2 * z}));
    if (p.key().find(".2.weight") != std::string::npos) CHECK(s == torch::IntArrayRef({1, 128}));
  }
  REQUIRE(mica->lambda.sizes() == torch::IntArrayRef({3, 3}));
  CHECK(torch::all(mica->lambda == 0.5).item<bool>());
  CHECK(mica->lambda.requires_grad());
  const MicaOutput out = mica(torch::randn({4, 3, z}), torch::ones({4, 3}));
  CHECK(out.fused.sizes() == torch::IntArrayRef({4, 3, z}));
  CHECK(out.attention.sizes() == torch::IntArrayRef({4, 3, 3}));
  out.fused.pow(2).sum().backward();
  REQUIRE(mica->lambda.grad().defined());
  for (int m = 0; m < 3; ++m)
    for (int n = 0; n < 3; ++n)
      if (m != n) CHECK(mica->lambda.grad()[m][n].item<float>() != 0.0f);
}

TEST_CASE("Mica: softmax over the other available modalities only", "[pipeline]") {
  InitTorch(1, 5);
  const int z = 8;
  Mica mica(3, z);
  torch::NoGradGuard no_grad;
  mica->lambda.uniform_(0.2, 1.5);  // distinct gains, so each term is checked
  const torch::Tensor mask = AllMasks();
  const torch::Tensor t = torch::randn({8, 3, z}) * mask.unsqueeze(-1);  // MADW zeroes missing
  const MicaOutput out = mica(t, mask);
  REQUIRE(AllFinite(out.fused));
  REQUIRE(AllFinite(out.attention));
  for (int p = 0; p < 8; ++p) {
    for (int m = 0; m < 3; ++m) {
      // Reference: g^m on each available partner n != m, softmax over those.
      std::vector<int> partners;
      std::vector<double> g;
      for (int n = 0; n < 3; ++n) {
        if (n == m || mask[p][n].item<float>() == 0.0f) continue;
        partners.push_back(n);
        const torch::Tensor pair = torch::cat({t[p][m], t[p][n]}).unsqueeze(0);
        g.push_back(mica->scores[static_cast<std::size_t>(m)]
                        ->as<torch::nn::Sequential>()
                        ->forward(pair)
                        .item<double>());
      }
      double denom = 0.0;
      for (double v : g) denom += std::exp(v);
      torch::Tensor expected = t[p][m].clone();
      for (int n = 0; n < 3; ++n) {
        double alpha = 0.0;
        for (std::size_t i = 0; i < partners.size(); ++i)
          if (partners[i] == n) alpha = std::exp(g[i]) / denom;
        CHECK(out.attention[p][m][n].item<double>() == Approx(alpha).margin(1e-6));
        if (alpha == 0.0) CHECK(out.attention[p][m][n].item<float>() == 0.0f);  // exactly
        expected += mica->lambda[m][n] * alpha * t[p][n];
      }
      CHECK(torch::allclose(out.fused[p][m], expected, 1e-5, 1e-6));
      if (partners.empty()) CHECK(torch::equal(out.fused[p][m], t[p][m]));  // residual alone
    }
  }
}

TEST_CASE("Mica: a missing modality contributes nothing, whatever its features", "[pipeline]") {
  InitTorch(1, 6);
  Mica mica(3, 8);
  torch::NoGradGuard no_grad;
  torch::Tensor mask = torch::tensor({{1.0f, 0.0f, 1.0f}});
  torch::Tensor t = torch::randn({1, 3, 8});
  torch::Tensor garbage = t.clone();
  garbage[0][1] = torch::randn({8}) * 1e3;
  const MicaOutput a = mica(t, mask);
  const MicaOutput b = mica(garbage, mask);
  CHECK(torch::equal(a.fused[0][0], b.fused[0][0]));
  CHECK(torch::equal(a.fused[0][2], b.fused[0][2]));
}

TEST_CASE("Madw + Mica: all-missing windows give zeros and no NaN, also in gradients",
          "[pipeline]") {
  InitTorch(1, 7);
  Madw madw(3, 8);
  Mica mica(3, 8);
  const torch::Tensor mask = torch::zeros({6, 3});
  const torch::Tensor latents = torch::randn({6, 3, 8});
  const MicaOutput out = mica(madw(latents, mask).weighted, mask);
  CHECK(out.fused.abs().max().item<float>() == 0.0f);
  CHECK(out.attention.abs().max().item<float>() == 0.0f);
  out.fused.sum().backward();
  for (const auto& p : madw->parameters())
    if (p.grad().defined()) CHECK(AllFinite(p.grad()));
  for (const auto& p : mica->parameters())
    if (p.grad().defined()) CHECK(AllFinite(p.grad()));
}

}  // namespace uavsim::pipeline
