// The fused selective scan (paper Sec. V-C, Eq. (27)) against the loop of
// LibTorch ops autograd differentiates (SelectiveScanReference): values,
// gradients of every input through both outputs, and central finite
// differences of the fused function itself.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/edge/selective_scan.h"
#include "pipeline/torch_runtime.h"

namespace uavsim::pipeline {
namespace {

constexpr const char* kInputNames[] = {"u", "delta", "A", "Bm", "Cm", "D_skip", "z", "delta_bias"};

// Random inputs in the ranges the block produces (A < 0, Δ's pre-activation
// around the initial softplus inverse), every one requiring a gradient.
std::vector<torch::Tensor> RandomInputs(int64_t b, int64_t d, int64_t n, int64_t l,
                                        torch::ScalarType dtype) {
  const auto o = torch::TensorOptions().dtype(dtype);
  std::vector<torch::Tensor> in = {
      torch::randn({b, d, l}, o),           // u
      torch::randn({b, d, l}, o),           // delta
      -torch::rand({d, n}, o) * 2.0 - 0.1,  // A
      torch::randn({b, n, l}, o),           // Bm
      torch::randn({b, n, l}, o),           // Cm
      torch::randn({d}, o),                 // D_skip
      torch::randn({b, d, l}, o),           // z
      torch::randn({d}, o) - 1.0,           // delta_bias
  };
  for (torch::Tensor& t : in) t.requires_grad_(true);
  return in;
}

using Scan = torch::Tensor (*)(const torch::Tensor&, const torch::Tensor&, const torch::Tensor&,
                               const torch::Tensor&, const torch::Tensor&, const torch::Tensor&,
                               const torch::Tensor&, const torch::Tensor&, torch::Tensor*);

torch::Tensor Run(Scan scan, const std::vector<torch::Tensor>& in, torch::Tensor* last) {
  return scan(in[0], in[1], in[2], in[3], in[4], in[5], in[6], in[7], last);
}

// A scalar that weighs every output and last-state element differently.
torch::Tensor Loss(Scan scan, const std::vector<torch::Tensor>& in, const torch::Tensor& w_out,
                   const torch::Tensor& w_last) {
  torch::Tensor last;
  const torch::Tensor out = Run(scan, in, &last);
  return (out * w_out).sum() + (last * w_last).sum();
}

std::vector<torch::Tensor> Gradients(Scan scan, const std::vector<torch::Tensor>& in,
                                     const torch::Tensor& w_out, const torch::Tensor& w_last) {
  return torch::autograd::grad({Loss(scan, in, w_out, w_last)}, in);
}

double MaxAbsDiff(const torch::Tensor& a, const torch::Tensor& b) {
  return a.numel() == 0 ? 0.0 : (a - b).abs().max().item<double>();
}

}  // namespace

TEST_CASE("SelectiveScan: the fused forward equals the reference in float32", "[pipeline]") {
  InitTorch(1, 31);
  for (int64_t b : {1, 3})
    for (int64_t d : {1, 8})
      for (int64_t n : {1, 4})
        for (int64_t l : {0, 1, 7, 30}) {
          const auto in = RandomInputs(b, d, n, l, torch::kFloat32);
          torch::NoGradGuard no_grad;
          torch::Tensor last, last_ref;
          const torch::Tensor out = Run(&SelectiveScan, in, &last);
          const torch::Tensor ref = Run(&SelectiveScanReference, in, &last_ref);
          INFO("B " << b << " D " << d << " N " << n << " L " << l);
          REQUIRE(out.sizes() == torch::IntArrayRef({b, d, l}));
          REQUIRE(last.sizes() == torch::IntArrayRef({b, d, n}));
          CHECK(out.scalar_type() == torch::kFloat32);
          CHECK(MaxAbsDiff(out, ref) < 1e-5);
          CHECK(MaxAbsDiff(last, last_ref) < 1e-5);
          if (l == 0) CHECK(last.abs().max().item<float>() == 0.0f);
        }
}

TEST_CASE("SelectiveScan: fused gradients equal autograd through the reference", "[pipeline]") {
  InitTorch(1, 32);
  for (int64_t b : {1, 2, 3})
    for (int64_t d : {1, 5})
      for (int64_t n : {1, 3})
        for (int64_t l : {1, 7, 30}) {
          auto in = RandomInputs(b, d, n, l, torch::kFloat64);
          if (l > 1) {
            // One pre-activation above softplus' threshold of 20 (Δ = x there).
            torch::NoGradGuard no_grad;
            in[1][0][0][1] = 25.0;
          }
          const torch::Tensor w_out = torch::randn({b, d, l}, torch::kFloat64);
          const torch::Tensor w_last = torch::randn({b, d, n}, torch::kFloat64);
          const auto fused = Gradients(&SelectiveScan, in, w_out, w_last);
          const auto ref = Gradients(&SelectiveScanReference, in, w_out, w_last);
          for (std::size_t i = 0; i < in.size(); ++i) {
            INFO("B " << b << " D " << d << " N " << n << " L " << l << ": d/d" << kInputNames[i]);
            REQUIRE(fused[i].sizes() == in[i].sizes());
            // With one step h_0 = 0, so A gets no gradient; else every input does.
            if (l > 1) CHECK(fused[i].abs().max().item<double>() > 0.0);
            CHECK(MaxAbsDiff(fused[i], ref[i]) < 1e-5);
          }
        }
}

TEST_CASE("SelectiveScan: fused gradients equal central finite differences", "[pipeline]") {
  InitTorch(1, 33);
  const int64_t b = 2, d = 3, n = 2, l = 6;
  const auto in = RandomInputs(b, d, n, l, torch::kFloat64);
  const torch::Tensor w_out = torch::randn({b, d, l}, torch::kFloat64);
  const torch::Tensor w_last = torch::randn({b, d, n}, torch::kFloat64);
  const auto analytic = Gradients(&SelectiveScan, in, w_out, w_last);
  const double eps = 1e-6;
  torch::NoGradGuard no_grad;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const torch::Tensor flat = in[i].view({-1});
    const torch::Tensor grad = analytic[i].reshape({-1});
    double worst = 0.0;
    for (int64_t k = 0; k < flat.numel(); ++k) {
      const double x = flat[k].item<double>();
      flat[k] = x + eps;
      const double plus = Loss(&SelectiveScan, in, w_out, w_last).item<double>();
      flat[k] = x - eps;
      const double minus = Loss(&SelectiveScan, in, w_out, w_last).item<double>();
      flat[k] = x;
      const double numeric = (plus - minus) / (2.0 * eps);
      const double exact = grad[k].item<double>();
      worst = std::max(worst, std::abs(numeric - exact) / (1.0 + std::abs(exact)));
    }
    INFO("d/d" << kInputNames[i]);
    CHECK(worst < 1e-6);
  }
}

TEST_CASE("SelectiveScan: values and gradients do not depend on the thread count", "[pipeline]") {
  InitTorch(1, 35);
  const auto in = RandomInputs(5, 16, 4, 20, torch::kFloat32);
  const torch::Tensor w_out = torch::randn({5, 16, 20});
  const torch::Tensor w_last = torch::randn({5, 16, 4});
  const int threads = at::get_num_threads();
  std::vector<std::vector<torch::Tensor>> runs;
  for (int n : {1, 2, 3}) {
    at::set_num_threads(n);
    torch::Tensor last;
    std::vector<torch::Tensor> run = Gradients(&SelectiveScan, in, w_out, w_last);
    run.push_back(Run(&SelectiveScan, in, &last).detach());
    run.push_back(last.detach());
    runs.push_back(run);
  }
  at::set_num_threads(threads);
  for (std::size_t r = 1; r < runs.size(); ++r)
    for (std::size_t i = 0; i < runs[0].size(); ++i) CHECK(torch::equal(runs[r][i], runs[0][i]));
}

TEST_CASE("SelectiveScan: strided views, L = 0 and shape errors", "[pipeline]") {
  InitTorch(1, 34);
  // The block passes transposed views; the fused scan reads them as such.
  const torch::Tensor u = torch::randn({2, 9, 4}).transpose(1, 2);  // [2, 4, 9]
  const torch::Tensor delta = torch::randn({2, 9, 4}).transpose(1, 2);
  const torch::Tensor z = torch::randn({2, 9, 4}).transpose(1, 2);
  const torch::Tensor A = -torch::rand({4, 3}) - 0.5;
  const torch::Tensor Bm = torch::randn({2, 9, 3}).transpose(1, 2);
  const torch::Tensor Cm = torch::randn({2, 9, 3}).transpose(1, 2);
  const torch::Tensor D = torch::randn({4});
  const torch::Tensor bias = torch::randn({4});
  REQUIRE(!u.is_contiguous());
  const torch::Tensor fused = SelectiveScan(u, delta, A, Bm, Cm, D, z, bias);
  const torch::Tensor ref = SelectiveScanReference(u, delta, A, Bm, Cm, D, z, bias);
  CHECK(MaxAbsDiff(fused, ref) < 1e-5);

  // L = 0: an empty output, a zero last state, and gradients of zeros.
  auto empty = RandomInputs(2, 3, 2, 0, torch::kFloat64);
  torch::Tensor last;
  const torch::Tensor out = Run(&SelectiveScan, empty, &last);
  CHECK(out.sizes() == torch::IntArrayRef({2, 3, 0}));
  CHECK(last.abs().max().item<double>() == 0.0);
  const auto grads = torch::autograd::grad({(last * 2.0).sum()}, empty, {}, false, false, true);
  for (std::size_t i = 0; i < grads.size(); ++i)
    if (grads[i].defined() && grads[i].numel() > 0)
      CHECK(grads[i].abs().max().item<double>() == 0.0);

  // Shapes that do not fit are refused.
  CHECK_THROWS_WITH(SelectiveScan(u, delta, A, Bm.narrow(2, 0, 8), Cm, D, z, bias),
                    Catch::Contains("Bm and Cm must be"));
}

}  // namespace uavsim::pipeline
