// The UAVLoc edge network end to end (paper Sec. V): shapes, all-missing
// windows without NaN, the online step against the batch forward, a small
// training run, save/load, determinism and the torch-free facade.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/edge_localizer.h"
#include "pipeline/torch_runtime.h"
#include "pipeline/uavloc_model.h"
#include "sim/core/error.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

UavLocModelConfig SmallConfig(int z = 8) {
  UavLocModelConfig c;
  c.latent_dim = z;
  c.d_model = 32;
  c.layers = 2;
  return c;
}

bool AllFinite(const torch::Tensor& t) { return torch::isfinite(t).all().item<bool>(); }

// A window with 6 camera, 2 LiDAR and 3 radar frames (30, 10, 15 Hz), any
// modality dropped with probability `drop`; latents from `gen`.
WindowInputs RandomWindow(std::int64_t k, int z, double drop, torch::Generator& gen) {
  WindowInputs w;
  w.window = k;
  const int counts[3] = {6, 2, 3};
  const double start = (k - 1) * 0.2;
  for (int m = 0; m < 3; ++m) {
    if (torch::rand({1}, gen).item<double>() < drop) continue;
    for (int i = 0; i < counts[m]; ++i) {
      LatentFrame f;
      f.t_s = start + 0.2 * (i + 0.5) / counts[m];
      const torch::Tensor t = torch::randn({z}, gen);
      f.latent.assign(t.data_ptr<float>(), t.data_ptr<float>() + z);
      w.frames[static_cast<std::size_t>(m)].push_back(f);
    }
  }
  return w;
}

}  // namespace

TEST_CASE("UavLocModel: shapes of the batch forward and of the fusion", "[pipeline]") {
  InitTorch(1, 21);
  UavLocModel model(SmallConfig(16));
  const torch::Tensor latents = torch::randn({4, 10, 3, 16});
  const torch::Tensor mask = torch::bernoulli(torch::full({4, 10, 3}, 0.7));
  CHECK(model->Fuse(latents[0], mask[0]).sizes() == torch::IntArrayRef({10, 48}));
  CHECK(model(latents, mask).sizes() == torch::IntArrayRef({4, 10, 3}));
  CHECK(model->regressor->embed->weight.sizes() == torch::IntArrayRef({32, 48}));
  CHECK(model->regressor->head->weight.sizes() == torch::IntArrayRef({3, 32}));
}

TEST_CASE("UavLocModel: all-missing windows give no NaN in outputs or gradients", "[pipeline]") {
  InitTorch(1, 22);
  UavLocModel model(SmallConfig());
  const torch::Tensor latents = torch::randn({2, 12, 3, 8});
  torch::Tensor mask = torch::ones({2, 12, 3});
  mask.slice(1, 3, 9).zero_();  // six windows with nothing at all
  mask[1].zero_();              // a whole sequence with nothing at all
  const torch::Tensor out = model(latents, mask);
  REQUIRE(AllFinite(out));
  out.pow(2).sum().backward();
  for (const auto& p : model->named_parameters())
    if (p.value().grad().defined()) CHECK(AllFinite(p.value().grad()));

  model->ResetState();
  WindowInputs empty;
  for (std::int64_t k = 1; k <= 20; ++k) {
    empty.window = k;
    CHECK(model->Step(empty).allFinite());
  }
}

TEST_CASE("UavLocModel: the online Step equals the batch forward on aligned windows",
          "[pipeline]") {
  InitTorch(1, 23);
  UavLocModelConfig config = SmallConfig();
  config.position_centre_m = {10.0, -5.0, 30.0};
  config.position_scale_m = 20.0;
  UavLocModel model(config);
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(5);
  std::vector<AlignedWindow> aligned;
  std::vector<Eigen::Vector3d> online;
  for (std::int64_t k = 1; k <= 60; ++k) {
    const WindowInputs w = RandomWindow(k, 8, 0.3, gen);
    aligned.push_back(model->te_align().Align(w));
    online.push_back(model->Step(w));
  }
  const FusionBatch batch = StackWindows({aligned});
  torch::NoGradGuard no_grad;
  const torch::Tensor metres = model->PositionInMetres(model(batch.latents, batch.mask));
  double worst = 0.0;
  for (std::int64_t k = 0; k < 60; ++k)
    for (int i = 0; i < 3; ++i)
      worst = std::max(
          worst, std::abs(metres[0][k][i].item<double>() - online[static_cast<std::size_t>(k)][i]));
  CHECK(worst < 1e-5 * 20.0);  // 1e-5 in normalised units
}

TEST_CASE("UavLocModel: skipped windows are stepped as empty windows", "[pipeline]") {
  InitTorch(1, 24);
  UavLocModel model(SmallConfig());
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(6);
  const WindowInputs w1 = RandomWindow(1, 8, 0.0, gen);
  const WindowInputs w5 = RandomWindow(5, 8, 0.0, gen);
  model->Step(w1);
  const Eigen::Vector3d skipped = model->Step(w5);
  model->ResetState();
  model->Step(w1);
  WindowInputs empty;
  for (std::int64_t k = 2; k <= 4; ++k) {
    empty.window = k;
    model->Step(empty);
  }
  CHECK((model->Step(w5) - skipped).norm() < 1e-6);
  CHECK_THROWS_WITH(model->Step(w5), Catch::Contains("does not follow window 5"));
}

TEST_CASE("UavLocModel: a short training run lowers the loss tenfold", "[pipeline]") {
  // Synthetic tracking: each window's three modalities observe the UAV's
  // displacement in that window with different noise and are dropped at
  // random; the target is the position, the running sum of displacements.
  // Only the recurrence can solve it.
  InitTorch(1, 25);
  UavLocModelConfig config;
  config.latent_dim = 4;
  config.d_model = 32;
  config.layers = 1;
  UavLocModel model(config);
  const int64_t windows = 20, z = 4;
  auto make_batch = [&](int64_t batch, torch::Tensor* latents, torch::Tensor* mask,
                        torch::Tensor* target) {
    const torch::Tensor step = torch::randn({batch, windows, 3}) * 0.3;
    *target = step.cumsum(1);
    const torch::Tensor noise = torch::tensor({0.02f, 0.05f, 0.1f}).view({1, 1, 3, 1});
    torch::Tensor obs = step.unsqueeze(2).expand({batch, windows, 3, 3}) +
                        noise * torch::randn({batch, windows, 3, 3});
    *latents = torch::cat({obs, torch::zeros({batch, windows, 3, z - 3})}, -1);
    *mask = torch::bernoulli(torch::full({batch, windows, 3}, 0.85));
    *latents = *latents * mask->unsqueeze(-1);
  };
  torch::Tensor val_latents, val_mask, val_target;
  make_batch(64, &val_latents, &val_mask, &val_target);
  auto val_loss = [&] {
    torch::NoGradGuard no_grad;
    return torch::mse_loss(model(val_latents, val_mask), val_target).item<double>();
  };
  const double initial = val_loss();
  // A rate well above the paper's 1e-4, so that a few seconds suffice.
  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(5e-3));
  for (int it = 0; it < 200; ++it) {
    torch::Tensor latents, mask, target;
    make_batch(8, &latents, &mask, &target);
    adam.zero_grad();
    const torch::Tensor loss = torch::mse_loss(model(latents, mask), target);
    loss.backward();
    adam.step();
  }
  const double final_loss = val_loss();
  INFO("initial " << initial << ", final " << final_loss);
  CHECK(final_loss * 10.0 <= initial);
}

TEST_CASE("UavLocModel: save and load round trip, with the JSON sidecar", "[pipeline]") {
  InitTorch(1, 26);
  UavLocModelConfig config = SmallConfig();
  config.position_centre_m = {1.0, 2.0, 3.0};
  config.position_scale_m = 50.0;
  UavLocModel model(config);
  {
    torch::NoGradGuard no_grad;
    model->mica->lambda.fill_(0.75);
  }
  const std::string dir = testing::TempDir("fusion_model");
  const std::string path = dir + "/uavloc.pt";
  SaveUavLocModel(model, path);
  REQUIRE(std::filesystem::is_regular_file(path));
  REQUIRE(std::filesystem::is_regular_file(SidecarPath(path)));
  const std::string sidecar = testing::ReadFile(SidecarPath(path));
  CHECK_THAT(sidecar, Catch::Contains("\"position_scale_m\": 50"));
  CHECK_THAT(sidecar, Catch::Contains("\"format\": \"uavloc-model/1\""));

  UavLocModel loaded = LoadUavLocModel(path);
  CHECK(loaded->config().position_centre_m == config.position_centre_m);
  CHECK(loaded->config().d_model == 32);
  const auto a = model->named_parameters();
  const auto b = loaded->named_parameters();
  REQUIRE(a.size() == b.size());
  for (const auto& p : a) CHECK(torch::equal(p.value(), b[p.key()]));
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(7);
  for (std::int64_t k = 1; k <= 5; ++k) {
    const WindowInputs w = RandomWindow(k, 8, 0.2, gen);
    CHECK(model->Step(w) == loaded->Step(w));
  }

  // A sidecar that disagrees with the weights is refused with the file named.
  UavLocModelConfig other = config;
  other.d_model = 16;
  SaveUavLocModel(UavLocModel(other), dir + "/other.pt");
  std::filesystem::copy_file(SidecarPath(dir + "/other.pt"), SidecarPath(path),
                             std::filesystem::copy_options::overwrite_existing);
  CHECK_THROWS_WITH(LoadUavLocModel(path), Catch::Contains(path));
  testing::WriteFile(SidecarPath(path), "{\"format\": \"uavloc-model/1\", \"d_modle\": 3}");
  CHECK_THROWS_WITH(LoadUavLocModel(path), Catch::Contains("d_modle"));
  CHECK_THROWS_AS(LoadUavLocModel(dir + "/missing.pt"), core::ConfigError);
}

TEST_CASE("UavLocModel: the same seed gives the same model and outputs", "[pipeline]") {
  InitTorch(1, 27);
  torch::manual_seed(99);
  UavLocModel a(SmallConfig());
  const torch::Tensor x = torch::randn({2, 6, 3, 8});
  torch::manual_seed(99);
  UavLocModel b(SmallConfig());
  const torch::Tensor mask = torch::ones({2, 6, 3});
  for (const auto& p : a->named_parameters())
    CHECK(torch::equal(p.value(), b->named_parameters()[p.key()]));
  CHECK(torch::equal(a(x, mask), b(x, mask)));
  torch::manual_seed(100);
  UavLocModel c(SmallConfig());
  CHECK(!torch::equal(a(x, mask), c(x, mask)));
}

TEST_CASE("EdgeLocalizer: loads a model and localizes window by window", "[pipeline]") {
  InitTorch(1, 28);
  UavLocModelConfig config = SmallConfig();
  config.position_centre_m = {0.0, 0.0, 40.0};
  UavLocModel model(config);
  const std::string path = testing::TempDir("edge_localizer") + "/m.pt";
  SaveUavLocModel(model, path);
  const auto localizer = EdgeLocalizer::Load(path);
  CHECK(localizer->latent_dim() == 8);
  CHECK(localizer->window_s() == 0.2);
  WindowInputs empty;
  empty.window = 1;
  CHECK(!localizer->OnWindow(empty).has_value());  // nothing seen yet
  model->Step(empty);
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(8);
  const WindowInputs w2 = RandomWindow(2, 8, 0.0, gen);
  const auto p = localizer->OnWindow(w2);
  REQUIRE(p.has_value());
  CHECK(*p == model->Step(w2));  // the facade is the model, loaded
  empty.window = 3;
  CHECK(localizer->OnWindow(empty).has_value());  // carried by the state
  localizer->Reset();
  empty.window = 4;
  CHECK(!localizer->OnWindow(empty).has_value());
  WindowInputs bad = RandomWindow(5, 8, 0.0, gen);
  bad.frames[0][0].latent.resize(3);
  CHECK_THROWS_WITH(localizer->OnWindow(bad), Catch::Contains("expected z = 8"));
}

}  // namespace uavsim::pipeline
