// IB-CC modules (paper Sec. IV-B, Table I): shapes, the KL term against its
// closed form, masked max pooling, reparameterisation statistics, the MLP
// baseline's parameter count, a small training run and determinism.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "pipeline/node/ib_encoder.h"
#include "pipeline/node/ib_normalization.h"
#include "pipeline/torch_runtime.h"

namespace uavsim::pipeline {
namespace {

constexpr int kLatentSizes[] = {4, 8, 16, 32, 64};

IbInput RandomCameraInput(std::int64_t b) {
  IbInput in;
  in.left = torch::rand({b, 1, 128, 128});
  in.right = torch::rand({b, 1, 128, 128});
  in.geometry = torch::randn({b, kCameraGeometryFeatures});
  return in;
}

IbInput RandomPointInput(std::int64_t b, std::int64_t channels, std::int64_t n) {
  IbInput in;
  in.points = torch::randn({b, channels, n});
  in.mask = torch::ones({b, n}, torch::kBool);
  return in;
}

IbCcConfig Config(Modality m, int z, IbBottleneck bottleneck = IbBottleneck::kIb) {
  IbCcConfig c;
  c.modality = m;
  c.latent_dim = z;
  c.bottleneck = bottleneck;
  return c;
}

}  // namespace

TEST_CASE("ImageFeatureEncoder: Table I feature maps and output shapes", "[pipeline]") {
  InitTorch(1, 1);
  ImageFeatureEncoder enc;
  for (std::int64_t b : {1, 8}) {
    const IbInput in = RandomCameraInput(b);
    const std::vector<torch::Tensor> maps = enc->FeatureMaps(in.left);
    REQUIRE(maps.size() == 2);
    CHECK(maps[0].sizes() == torch::IntArrayRef({b, 32, 64, 64}));
    CHECK(maps[1].sizes() == torch::IntArrayRef({b, 64, 32, 32}));
    CHECK(maps[1].min().item<float>() >= 0.0f);  // ReLU
    const torch::Tensor h = enc->forward(in.left, in.right, in.geometry);
    CHECK(h.sizes() == torch::IntArrayRef({b, 2 * 1024 + kCameraGeometryFeatures}));
    CHECK(enc->features() == 2066);
  }
}

TEST_CASE("ImageFeatureEncoder: eyes share weights, order is kept, geometry is appended",
          "[pipeline]") {
  InitTorch(1, 2);
  ImageFeatureEncoder enc;
  enc->eval();
  const IbInput in = RandomCameraInput(2);
  const torch::Tensor h = enc->forward(in.left, in.right, in.geometry);
  const torch::Tensor swapped = enc->forward(in.right, in.left, in.geometry);
  // Shared weights: swapping the eyes swaps the two 1024-feature halves.
  CHECK(torch::allclose(h.slice(1, 0, 1024), swapped.slice(1, 1024, 2048)));
  CHECK(torch::allclose(h.slice(1, 1024, 2048), swapped.slice(1, 0, 1024)));
  CHECK(torch::equal(h.slice(1, 2048), in.geometry));
}

TEST_CASE("ImageFeatureEncoder: the paper's layout, two branches, no pool, no geometry",
          "[pipeline]") {
  InitTorch(1, 2);
  ImageFeatureEncoder enc(0.1, StereoBranches::kTwo, 0, false);
  enc->eval();
  const IbInput in = RandomCameraInput(2);
  const torch::Tensor h = enc->forward(in.left, in.right, in.geometry);
  // 2 eyes x 64 x 32 x 32, nothing appended (issue 20's hint for Table III).
  CHECK(enc->features() == 2 * 64 * 32 * 32);
  CHECK(h.sizes() == torch::IntArrayRef({2, 131072}));
  // Unpooled: the left half is the left branch's last map, flattened.
  CHECK(torch::allclose(h.slice(1, 0, 65536), enc->FeatureMaps(in.left).back().flatten(1)));
  CHECK(torch::allclose(h.slice(1, 65536), enc->FeatureMaps(in.right, true).back().flatten(1)));
  // Two branches: each eye has its own weights (two sets of Table I's convs,
  // 2 x (1*32*9 + 32 + 32*64*9 + 64) parameters), so swapping the eyes does
  // not merely swap the halves.
  std::int64_t parameters = 0;
  for (const torch::Tensor& p : enc->parameters()) parameters += p.numel();
  CHECK(parameters == 2 * (1 * 32 * 9 + 32 + 32 * 64 * 9 + 64));
  const torch::Tensor swapped = enc->forward(in.right, in.left, in.geometry);
  CHECK_FALSE(torch::allclose(h.slice(1, 0, 65536), swapped.slice(1, 65536)));
  // Changing the geometry changes nothing without roi_geometry.
  CHECK(torch::equal(h, enc->forward(in.left, in.right, in.geometry + 1.0)));
  // A pool side that does not divide 32 is refused.
  CHECK_THROWS_AS(ImageFeatureEncoder(0.1, StereoBranches::kTwo, 3, false), std::invalid_argument);
}

TEST_CASE("IbCcModel: the camera switches set the bottleneck's input width", "[pipeline]") {
  InitTorch(1, 2);
  const auto count = [](IbCcModel& m) {
    std::int64_t n = 0;
    for (const torch::Tensor& p : m->parameters()) n += p.numel();
    return n;
  };
  IbCcConfig ours;
  ours.modality = Modality::kCamera;
  ours.latent_dim = 16;
  IbCcConfig paper = ours;
  paper.stereo_branches = StereoBranches::kTwo;
  paper.eye_pool_side = 0;
  paper.roi_geometry = false;
  IbCcModel a(ours), b(paper);
  // Hand count: convs, mu and sigma MLPs Linear(d, 128) -> Linear(128, z),
  // decoder Linear(z, 128) -> Linear(128, 64) -> Linear(64, 3).
  const auto expected = [](std::int64_t convs, std::int64_t d) {
    const std::int64_t z = 16, conv = 1 * 32 * 9 + 32 + 32 * 64 * 9 + 64;
    return convs * conv + 2 * (d * 128 + 128 + 128 * z + z) +
           (z * 128 + 128 + 128 * 64 + 64 + 64 * 3 + 3);
  };
  CHECK(count(a) == expected(1, 2 * 1024 + 18));
  CHECK(count(b) == expected(2, 2 * 65536));
  const IbInput in = RandomCameraInput(3);
  b->eval();
  CHECK(b->Encode(in).sizes() == torch::IntArrayRef({3, 16}));
}

TEST_CASE("PointNetEncoder: 1024-d global feature for LiDAR and radar", "[pipeline]") {
  InitTorch(1, 3);
  for (std::int64_t channels : {4, 5}) {
    PointNetEncoder enc(channels);
    for (std::int64_t b : {1, 8}) {
      for (std::int64_t n : {1024, 37}) {
        const IbInput in = RandomPointInput(b, channels, n);
        enc->train();
        CHECK(enc->forward(in.points, in.mask).sizes() == torch::IntArrayRef({b, 1024}));
        enc->eval();
        CHECK(enc->forward(in.points, in.mask).sizes() == torch::IntArrayRef({b, 1024}));
      }
    }
  }
}

TEST_CASE("IbHead, MlpCompressor and IbDecoder: mu, sigma of size z, decoder 3", "[pipeline]") {
  InitTorch(1, 4);
  for (int z : kLatentSizes) {
    for (std::int64_t b : {1, 8}) {
      const torch::Tensor h = torch::randn({b, 1024});
      IbHead head(1024, z);
      const IbHeadOutput out = head->forward(h);
      CHECK(out.mu.sizes() == torch::IntArrayRef({b, z}));
      CHECK(out.sigma.sizes() == torch::IntArrayRef({b, z}));
      CHECK(out.t.sizes() == torch::IntArrayRef({b, z}));
      CHECK(out.sigma.min().item<float>() > 0.0f);
      MlpCompressor mlp(1024, z);
      const IbHeadOutput code = mlp->forward(h);
      CHECK(code.mu.sizes() == torch::IntArrayRef({b, z}));
      CHECK_FALSE(code.sigma.defined());
      IbDecoder dec(z);
      CHECK(dec->forward(out.t).sizes() == torch::IntArrayRef({b, 3}));
    }
  }
}

TEST_CASE("IbCcModel: end-to-end shapes per modality, batch 1 and 8", "[pipeline]") {
  InitTorch(1, 5);
  for (Modality m : {Modality::kCamera, Modality::kLidar, Modality::kRadar}) {
    for (IbBottleneck bn : {IbBottleneck::kIb, IbBottleneck::kMlp}) {
      IbCcModel model(Config(m, 16, bn));
      model->eval();
      for (std::int64_t b : {1, 8}) {
        const IbInput in = m == Modality::kCamera ? RandomCameraInput(b)
                                                  : RandomPointInput(b, PointChannels(m), 64);
        const IbOutput out = model->forward(in);
        CHECK(out.features.sizes() == torch::IntArrayRef({b, model->feature_dim()}));
        CHECK(out.mu.sizes() == torch::IntArrayRef({b, 16}));
        CHECK(out.t.sizes() == torch::IntArrayRef({b, 16}));
        CHECK(out.y_hat.sizes() == torch::IntArrayRef({b, 3}));
        CHECK(out.sigma.defined() == (bn == IbBottleneck::kIb));
        CHECK(torch::equal(model->Encode(in), out.mu));
      }
    }
  }
}

TEST_CASE("KlDivergence: equals the closed form computed in doubles", "[pipeline]") {
  InitTorch(1, 6);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.5);
  std::uniform_real_distribution<double> uniform(0.05, 3.0);
  const int b = 5, z = 16;
  std::vector<float> mu(b * z), sigma(b * z);
  for (int i = 0; i < b * z; ++i) {
    mu[i] = static_cast<float>(normal(rng));
    sigma[i] = static_cast<float>(uniform(rng));
  }
  const torch::Tensor kl = KlDivergence(torch::from_blob(mu.data(), {b, z}).clone(),
                                        torch::from_blob(sigma.data(), {b, z}).clone());
  REQUIRE(kl.sizes() == torch::IntArrayRef({b}));
  for (int r = 0; r < b; ++r) {
    double expected = 0.0;
    for (int j = 0; j < z; ++j) {
      const double m = mu[r * z + j], s = sigma[r * z + j];
      expected += 0.5 * (m * m + s * s - std::log(s * s) - 1.0);
    }
    CHECK(kl[r].item<double>() == Approx(expected).epsilon(1e-5));
  }
}

TEST_CASE("KlDivergence: exactly zero for mu = 0, sigma = 1", "[pipeline]") {
  InitTorch(1, 7);
  const torch::Tensor kl = KlDivergence(torch::zeros({3, 64}), torch::ones({3, 64}));
  CHECK(torch::equal(kl, torch::zeros({3})));
  CHECK_THROWS_AS(KlDivergence(torch::zeros({3, 4}), torch::ones({3, 5})), std::invalid_argument);
}

TEST_CASE("PointNetEncoder: padding never reaches the output", "[pipeline]") {
  InitTorch(1, 8);
  PointNetEncoder enc(4);
  const torch::Tensor real = torch::randn({1, 4, 5});
  const torch::Tensor full_mask = torch::ones({1, 5}, torch::kBool);
  for (float junk : {1e30f, -1e30f, std::numeric_limits<float>::quiet_NaN()}) {
    torch::Tensor padded = torch::full({1, 4, 16}, junk);
    padded.slice(2, 0, 5).copy_(real);
    torch::Tensor mask = torch::zeros({1, 16}, torch::kBool);
    mask.slice(1, 0, 5).fill_(true);
    for (bool training : {true, false}) {
      enc->train(training);
      const torch::Tensor expected = enc->forward(real, full_mask);
      const torch::Tensor got = enc->forward(padded, mask);
      CHECK(torch::allclose(got, expected, 1e-6, 1e-6));
    }
  }
  // Clouds of different sizes in one batch: each row as if alone (eval mode).
  enc->eval();
  const torch::Tensor a = torch::randn({1, 4, 3});
  const torch::Tensor b = torch::randn({1, 4, 10});
  torch::Tensor batch = torch::full({2, 4, 10}, 1e30f);
  batch.slice(0, 0, 1).slice(2, 0, 3).copy_(a);
  batch.slice(0, 1, 2).copy_(b);
  torch::Tensor mask = torch::ones({2, 10}, torch::kBool);
  mask[0].slice(0, 3).fill_(false);
  const torch::Tensor out = enc->forward(batch, mask);
  CHECK(torch::allclose(out[0], enc->forward(a, torch::ones({1, 3}, torch::kBool))[0], 1e-6, 1e-6));
  CHECK(
      torch::allclose(out[1], enc->forward(b, torch::ones({1, 10}, torch::kBool))[0], 1e-6, 1e-6));
}

TEST_CASE("PointNetEncoder: eval-mode BatchNorm folding equals Conv1d, BN, ReLU", "[pipeline]") {
  InitTorch(1, 16);
  namespace F = torch::nn::functional;
  PointNetEncoder enc(5);
  torch::NoGradGuard no_grad;
  auto params = enc->named_parameters();
  auto buffers = enc->named_buffers();
  auto randomize_statistics = [&] {
    for (int l = 1; l <= 5; ++l) {
      const std::string bn = "bn" + std::to_string(l);
      params[bn + ".weight"].uniform_(0.5, 2.0);
      params[bn + ".bias"].normal_(0.0, 0.3);
      buffers[bn + ".running_mean"].normal_(0.0, 0.5);
      buffers[bn + ".running_var"].uniform_(0.2, 3.0);
    }
  };
  // Table I written out with functional ops from the module's own tensors.
  auto reference = [&](const torch::Tensor& x) {
    torch::Tensor h = x;
    for (int l = 1; l <= 5; ++l) {
      const std::string bn = "bn" + std::to_string(l);
      h = F::conv1d(h, params["conv" + std::to_string(l) + ".weight"]);
      h = F::batch_norm(h, buffers[bn + ".running_mean"], buffers[bn + ".running_var"],
                        F::BatchNormFuncOptions()
                            .weight(params[bn + ".weight"])
                            .bias(params[bn + ".bias"])
                            .training(false)
                            .eps(1e-5));
      h = torch::relu(h);
    }
    return h.amax(2);
  };
  const torch::Tensor x = torch::randn({3, 5, 200});
  const torch::Tensor mask = torch::ones({3, 200}, torch::kBool);
  randomize_statistics();
  enc->eval();
  CHECK(torch::allclose(enc->forward(x, mask), reference(x), 1e-4, 1e-5));
  // New weights in eval mode: eval() again refreshes the folded cache.
  randomize_statistics();
  enc->eval();
  CHECK(torch::allclose(enc->forward(x, mask), reference(x), 1e-4, 1e-5));
}

TEST_CASE("PointNetEncoder: the centroid frame's features do not move with the cloud",
          "[pipeline]") {
  InitTorch(1, 17);
  for (PointNorm norm : {PointNorm::kBatch, PointNorm::kGroup, PointNorm::kNone}) {
    INFO(PointNormName(norm));
    PointNetEncoder enc(4, PointFrame::kCentroid, norm);
    CHECK(enc->features() == 1027);
    // Two clouds of 7 and 12 points, padded to 12; channel 3 (intensity) kept.
    torch::Tensor x = torch::randn({2, 4, 12});
    torch::Tensor mask = torch::ones({2, 12}, torch::kBool);
    mask[0].slice(0, 7).fill_(false);
    const torch::Tensor shift = torch::tensor({3.0f, -2.0f, 0.5f});
    torch::Tensor moved = x.clone();
    moved.narrow(1, 0, 3).add_(shift.view({1, 3, 1}));
    torch::NoGradGuard no_grad;
    for (bool training : {true, false}) {
      enc->train(training);
      const torch::Tensor a = enc->forward(x, mask), b = enc->forward(moved, mask);
      CHECK(torch::allclose(a.narrow(1, 0, 1024), b.narrow(1, 0, 1024), 1e-4, 1e-5));
      // The appended centroid is the real points' mean, and moves with them.
      const torch::Tensor c0 = x[0].narrow(0, 0, 3).narrow(1, 0, 7).mean(1);
      CHECK(torch::allclose(a[0].narrow(0, 1024, 3), c0, 1e-5, 1e-6));
      CHECK(torch::allclose(b.narrow(1, 1024, 3) - a.narrow(1, 1024, 3),
                            shift.view({1, 3}).expand({2, 3}), 1e-4, 1e-5));
    }
  }
  // The scene frame (the paper's) does move: the check above can fail.
  PointNetEncoder scene(4);
  scene->eval();
  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::randn({1, 4, 9});
  torch::Tensor moved = x.clone();
  moved.narrow(1, 0, 3).add_(2.0);
  const torch::Tensor m = torch::ones({1, 9}, torch::kBool);
  CHECK_FALSE(torch::allclose(scene->forward(x, m), scene->forward(moved, m), 1e-4, 1e-5));
}

TEST_CASE("PointNetEncoder: with GroupNorm or no norm a cloud's features ignore its batch",
          "[pipeline]") {
  InitTorch(1, 18);
  for (PointNorm norm : {PointNorm::kGroup, PointNorm::kNone}) {
    INFO(PointNormName(norm));
    PointNetEncoder enc(5, PointFrame::kScene, norm);
    enc->train();  // BatchNorm would mix the batch here
    torch::NoGradGuard no_grad;
    const torch::Tensor a = torch::randn({1, 5, 6}), b = torch::randn({1, 5, 6}) * 5.0;
    const torch::Tensor m1 = torch::ones({1, 6}, torch::kBool);
    const torch::Tensor both =
        enc->forward(torch::cat({a, b}, 0), torch::ones({2, 6}, torch::kBool));
    CHECK(torch::allclose(both[0], enc->forward(a, m1)[0], 1e-5, 1e-6));
    // Eval mode (folded for kNone) gives the same as the module path.
    enc->eval();
    CHECK(torch::allclose(enc->forward(a, m1), both.narrow(0, 0, 1), 1e-4, 1e-5));
  }
}

TEST_CASE("PointNetEncoder: bad inputs are refused with a message", "[pipeline]") {
  InitTorch(1, 9);
  PointNetEncoder enc(5);
  CHECK_THROWS_WITH(enc->forward(torch::randn({2, 4, 8}), torch::ones({2, 8}, torch::kBool)),
                    Catch::Contains("expected [B, 5, N]"));
  CHECK_THROWS_WITH(enc->forward(torch::randn({2, 5, 8}), torch::ones({2, 8})),
                    Catch::Contains("bool tensor [2, 8]"));
  torch::Tensor mask = torch::ones({2, 8}, torch::kBool);
  mask[1].fill_(false);
  CHECK_THROWS_WITH(enc->forward(torch::randn({2, 5, 8}), mask),
                    Catch::Contains("at least one real point"));
}

TEST_CASE("IbHead: reparameterised samples have mean mu and variance sigma^2", "[pipeline]") {
  InitTorch(1, 10);
  IbHead head(8, 4);
  const std::int64_t n = 40000;
  const torch::Tensor h = torch::randn({1, 8}).expand({n, 8}).contiguous();
  torch::NoGradGuard no_grad;
  head->train();
  const IbHeadOutput out = head->forward(h);
  const torch::Tensor mu = out.mu[0], sigma = out.sigma[0];
  const torch::Tensor mean = out.t.to(torch::kDouble).mean(0);
  const torch::Tensor var = out.t.to(torch::kDouble).var(0);
  for (int j = 0; j < 4; ++j) {
    const double s = sigma[j].item<double>();
    const double se_mean = s / std::sqrt(static_cast<double>(n));
    const double se_var = s * s * std::sqrt(2.0 / static_cast<double>(n - 1));
    CHECK(std::abs(mean[j].item<double>() - mu[j].item<double>()) < 5.0 * se_mean);
    CHECK(std::abs(var[j].item<double>() - s * s) < 5.0 * se_var);
  }
  head->eval();
  const IbHeadOutput eval = head->forward(h.slice(0, 0, 4));
  CHECK(torch::equal(eval.t, eval.mu));
}

TEST_CASE("MlpCompressor: same depth and parameter count as IbHead within 1%", "[pipeline]") {
  InitTorch(1, 11);
  auto linear_layers = [](const torch::nn::Module& m) {
    int count = 0;
    for (const auto& child : m.modules(/*include_self=*/false))
      if (child->as<torch::nn::Linear>()) ++count;
    return count;
  };
  // The camera's width in our layout and in the paper's (no pool, no
  // geometry), and the point encoders'.
  const std::int64_t camera = ImageFeatureEncoder()->features();
  const std::int64_t paper_camera =
      ImageFeatureEncoder(0.1, StereoBranches::kTwo, 0, false)->features();
  for (std::int64_t d : {camera, paper_camera, PointNetEncoderImpl::kFeatures}) {
    for (int z : kLatentSizes) {
      IbHead head(d, z);
      MlpCompressor mlp(d, z);
      const double p_ib = static_cast<double>(ParameterCount(*head));
      const double p_mlp = static_cast<double>(ParameterCount(*mlp));
      INFO("d = " << d << ", z = " << z << ": IbHead " << p_ib << ", MLP " << p_mlp);
      CHECK(std::abs(p_mlp - p_ib) / p_ib < 0.01);
      // Depth: two layers for the MLP, two per branch (mu, sigma) for the head.
      CHECK(linear_layers(*mlp) == 2);
      CHECK(linear_layers(*head) == 4);
    }
  }
  for (Modality m : {Modality::kCamera, Modality::kLidar, Modality::kRadar}) {
    IbCcModel ib(Config(m, 8));
    IbCcModel mlp(Config(m, 8, IbBottleneck::kMlp));
    const double p_ib = static_cast<double>(ParameterCount(*ib));
    CHECK(std::abs(static_cast<double>(ParameterCount(*mlp)) - p_ib) / p_ib < 0.01);
  }
}

TEST_CASE("IbCcModel: the MLP baseline is deterministic and has no KL term", "[pipeline]") {
  InitTorch(1, 12);
  IbCcConfig c = Config(Modality::kLidar, 8, IbBottleneck::kMlp);
  c.dropout = 0.0;
  IbCcModel model(c);
  model->train();
  const IbInput in = RandomPointInput(4, 4, 32);
  const IbOutput a = model->forward(in);
  const IbOutput b = model->forward(in);
  CHECK(torch::equal(a.t, b.t));
  CHECK(torch::equal(a.t, a.mu));
  const IbLoss loss = model->Loss(a, torch::zeros({4, 3}));
  CHECK(loss.kl.item<float>() == 0.0f);
  CHECK(loss.total.item<float>() == loss.mse.item<float>());
}

TEST_CASE("IbCcModel: loss is MSE + beta KL and gradients reach every parameter", "[pipeline]") {
  InitTorch(1, 13);
  for (Modality m : {Modality::kCamera, Modality::kRadar}) {
    IbCcModel model(Config(m, 8));
    model->train();
    const IbInput in = m == Modality::kCamera ? RandomCameraInput(2) : RandomPointInput(2, 5, 16);
    const torch::Tensor y = torch::randn({2, 3});
    const IbOutput out = model->forward(in);
    const IbLoss loss = model->Loss(out, y);
    const double mse = (out.y_hat - y).square().sum(1).mean().item<double>();
    const double kl = KlDivergence(out.mu, out.sigma).mean().item<double>();
    CHECK(loss.mse.item<double>() == Approx(mse));
    CHECK(loss.total.item<double>() == Approx(mse + 1e-3 * kl));
    // In metres (the paper's equation with y in m): the normalised squared
    // error times scale_m^2, the same KL.
    IbCcConfig metres = model->config();
    metres.mse_units = IbMseUnits::kMetres;
    metres.normalization.scale_m = 13.5;
    IbCcModel in_metres(metres);
    const IbLoss m_loss = in_metres->Loss(out, y);
    CHECK(m_loss.mse.item<double>() == Approx(mse * 13.5 * 13.5));
    CHECK(m_loss.total.item<double>() == Approx(mse * 13.5 * 13.5 + 1e-3 * kl));
    loss.total.backward();
    for (const auto& p : model->named_parameters()) {
      INFO(ModalityName(m) << ": " << p.key());
      REQUIRE(p.value().grad().defined());
      CHECK(p.value().grad().abs().sum().item<double>() > 0.0);
    }
  }
}

TEST_CASE("IbCcModel: a small training run lowers the loss tenfold", "[pipeline][slow]") {
  InitTorch(1, 14);
  // 200 random world-frame LiDAR clouds of 4 to 16 points; the target is
  // their centroid.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> where(-10.0, 10.0);
  std::normal_distribution<double> spread(0.0, 1.0);
  std::uniform_int_distribution<int> size(4, 16);
  std::vector<PointObservation> clouds(200);
  std::vector<Eigen::Vector3d> centroids;
  for (auto& cloud : clouds) {
    const Eigen::Vector3d centre =
        Eigen::Vector3d(10.0, -20.0, 30.0) + Eigen::Vector3d(where(rng), where(rng), where(rng));
    const int n = size(rng);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = centre + Eigen::Vector3d(spread(rng), spread(rng), spread(rng));
      sum += p;
      for (int a = 0; a < 3; ++a) cloud.values.push_back(static_cast<float>(p[a]));
      cloud.values.push_back(0.5f);
    }
    centroids.push_back(sum / n);
  }
  IbCcConfig c = Config(Modality::kLidar, 8);
  c.normalization = FitPositionNormalization(centroids);
  std::vector<const PointObservation*> all;
  for (const auto& cloud : clouds) all.push_back(&cloud);
  const IbInput in = MakePointInput(all, Modality::kLidar, c.normalization);
  const torch::Tensor y = MakePositionTarget(centroids, c.normalization);

  IbCcModel model(c);
  auto eval_loss = [&] {
    torch::NoGradGuard no_grad;
    model->eval();
    return model->Loss(model->forward(in), y).total.item<double>();
  };
  const double before = eval_loss();
  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(1e-3));
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t batch = 20;
  for (int epoch = 0; epoch < 20; ++epoch) {
    model->train();
    // A tenfold smaller step for the last epochs lets the weights and the
    // BatchNorm running statistics settle.
    if (epoch == 15)
      for (auto& group : adam.param_groups())
        static_cast<torch::optim::AdamOptions&>(group.options()).lr(1e-4);
    const torch::Tensor order = torch::randperm(200, torch::kLong);
    for (std::int64_t s = 0; s < 200; s += batch) {
      const torch::Tensor idx = order.slice(0, s, s + batch);
      IbInput part;
      part.points = in.points.index_select(0, idx);
      part.mask = in.mask.index_select(0, idx);
      adam.zero_grad();
      const IbLoss loss = model->Loss(model->forward(part), y.index_select(0, idx));
      loss.total.backward();
      adam.step();
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double after = eval_loss();
  INFO("loss " << before << " -> " << after << " in " << seconds << " s");
  CHECK(after < before / 10.0);
}

TEST_CASE("IbCcModel: torch::manual_seed fixes weights, dropout and samples", "[pipeline]") {
  InitTorch(1, 15);
  auto run = [](std::uint64_t seed) {
    torch::manual_seed(seed);
    IbCcModel model(Config(Modality::kCamera, 16));
    model->train();
    const IbInput in = RandomCameraInput(3);
    const IbOutput out = model->forward(in);
    return torch::cat({out.t, out.y_hat}, 1);
  };
  CHECK(torch::equal(run(21), run(21)));
  CHECK_FALSE(torch::equal(run(21), run(22)));
}

}  // namespace uavsim::pipeline
