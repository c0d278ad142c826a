// The edge network's Sec. VI baselines and ablations (uavloc_model.h,
// fusion_kind.h): MADW / MICA switched off (Fig. 13), early fusion, late
// weighted fusion and HeMIS-style fusion (Fig. 14). Shapes and parameter
// counts against closed forms; one, two, three and no modality present (no
// NaN, and a missing modality's latent has no effect); the online Step
// against the batch forward; save and load.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "pipeline/edge/uavloc_model.h"
#include "pipeline/torch_runtime.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

constexpr int kZ = 8;

UavLocModelConfig Config(FusionKind fusion, bool madw = true, bool mica = true) {
  UavLocModelConfig c;
  c.latent_dim = kZ;
  c.d_model = 16;
  c.layers = 1;
  c.fusion = fusion;
  c.madw = madw;
  c.mica = mica;
  return c;
}

int64_t Parameters(torch::nn::Module& m) {
  int64_t n = 0;
  for (const torch::Tensor& p : m.parameters()) n += p.numel();
  return n;
}

// Regressor options as the model builds them, for a given input width.
int64_t RegressorParameters(int input_dim) {
  UavLocModelConfig c = Config(FusionKind::kUavLoc);
  MambaRegressorOptions r;
  r.input_dim = input_dim;
  r.output_dim = 3;
  r.layers = c.layers;
  r.mamba.d_model = c.d_model;
  r.mamba.d_state = c.d_state;
  r.mamba.d_conv = c.d_conv;
  r.mamba.expand = c.expand;
  TemporalRegressorOptions t;
  t.mamba = r;
  return ParameterCount(t);
}

// Score MLP of Table I: Linear(in, 128) -> ReLU -> Linear(128, 1).
int64_t ScoreMlpParameters(int in) { return in * 128 + 128 + 128 + 1; }

bool AllFinite(const torch::Tensor& t) { return torch::isfinite(t).all().item<bool>(); }

const std::vector<UavLocModelConfig>& AllKinds() {
  static const std::vector<UavLocModelConfig> kinds = {Config(FusionKind::kUavLoc),
                                                       Config(FusionKind::kUavLoc, false, true),
                                                       Config(FusionKind::kUavLoc, true, false),
                                                       Config(FusionKind::kUavLoc, false, false),
                                                       Config(FusionKind::kEarly),
                                                       Config(FusionKind::kLate),
                                                       Config(FusionKind::kHemis)};
  return kinds;
}

std::string Name(const UavLocModelConfig& c) {
  return std::string(FusionKindName(c.fusion)) + (c.madw ? "" : " no_madw") +
         (c.mica ? "" : " no_mica");
}

}  // namespace

TEST_CASE("Fusion variants: parameter counts equal their closed forms", "[pipeline]") {
  InitTorch(1, 3);
  const int64_t madw = 3 * ScoreMlpParameters(kZ);
  const int64_t mica = 3 * ScoreMlpParameters(2 * kZ) + 9;  // + λ [3, 3]
  const int64_t paper_regressor = RegressorParameters(3 * kZ);
  const int64_t d = HemisEmbedding(kZ);
  CHECK(d == 12);
  const std::vector<int64_t> expected = {
      madw + mica + paper_regressor,
      mica + paper_regressor,
      madw + paper_regressor,
      paper_regressor,
      3 * (kZ * kZ + kZ) + paper_regressor,          // early: Linear(z, z) per modality
      3 * RegressorParameters(kZ) + 3,               // late: a branch per modality + weights
      3 * (kZ * d + d) + RegressorParameters(2 * d)  // HeMIS: embeddings, [mean, var]
  };
  for (std::size_t i = 0; i < AllKinds().size(); ++i) {
    INFO(Name(AllKinds()[i]));
    UavLocModel model(AllKinds()[i]);
    CHECK(Parameters(*model) == expected[i]);
    CHECK(model->config().fused_dim() == (AllKinds()[i].fusion == FusionKind::kLate    ? kZ
                                          : AllKinds()[i].fusion == FusionKind::kHemis ? 2 * d
                                                                                       : 3 * kZ));
  }
}

TEST_CASE("Fusion variants: docs/training.md's parameter counts at the default sizes",
          "[pipeline]") {
  // z = 16, d_model 64, 2 layers (UavLocModelConfig's defaults).
  InitTorch(1, 3);
  const auto count = [](FusionKind fusion, bool madw, bool mica) {
    UavLocModelConfig c;
    c.fusion = fusion;
    c.madw = madw;
    c.mica = mica;
    UavLocModel model(c);
    return Parameters(*model);
  };
  CHECK(count(FusionKind::kUavLoc, true, true) == 88978);
  CHECK(count(FusionKind::kUavLoc, false, true) == 82063);
  CHECK(count(FusionKind::kUavLoc, true, false) == 75910);
  CHECK(count(FusionKind::kUavLoc, false, false) == 68995);
  CHECK(count(FusionKind::kEarly, true, true) == 69811);
  CHECK(count(FusionKind::kLate, true, true) == 200844);
  CHECK(count(FusionKind::kHemis, true, true) == 70219);
}

TEST_CASE("Fusion variants: every subset of modalities present, none missing too", "[pipeline]") {
  // For each variant and each of the 8 masks: the output is finite, the
  // gradient too, and a missing modality's latent (here: noise of size 100)
  // changes nothing.
  for (const UavLocModelConfig& config : AllKinds()) {
    INFO(Name(config));
    InitTorch(1, 5);
    UavLocModel model(config);
    for (int bits = 0; bits < 8; ++bits) {
      INFO("modalities present: " << bits);
      torch::Tensor mask = torch::zeros({2, 6, 3});
      for (int m = 0; m < 3; ++m)
        if (bits & (1 << m)) mask.select(2, m).fill_(1.0);
      torch::Tensor latents = torch::randn({2, 6, 3, kZ}) * mask.unsqueeze(-1);
      latents.requires_grad_(true);
      const torch::Tensor y = model(latents, mask);
      CHECK(y.sizes() == torch::IntArrayRef({2, 6, 3}));
      CHECK(AllFinite(y));
      y.sum().backward();
      CHECK(AllFinite(latents.grad()));
      for (const torch::Tensor& p : model->parameters())
        if (p.grad().defined()) CHECK(AllFinite(p.grad()));
      model->zero_grad();
      torch::NoGradGuard no_grad;
      const torch::Tensor noise = torch::randn({2, 6, 3, kZ}) * 100.0 * (1 - mask).unsqueeze(-1);
      CHECK(torch::allclose(model(latents.detach() + noise, mask), y.detach(), 1e-5, 1e-6));
    }
  }
}

TEST_CASE("Fusion baselines: what each fuses, by hand", "[pipeline]") {
  InitTorch(1, 7);
  torch::NoGradGuard no_grad;
  const torch::Tensor latents = torch::randn({4, 3, kZ});
  const torch::Tensor camera_only = torch::tensor({1.0f, 0.0f, 0.0f}).repeat({4, 1});
  const torch::Tensor none = torch::zeros({4, 3});
  {
    // Early fusion: a missing modality's slot of the concatenation is 0.
    UavLocModel model(Config(FusionKind::kEarly));
    const torch::Tensor f = model->Fuse(latents, camera_only);
    CHECK(f.sizes() == torch::IntArrayRef({4, 3 * kZ}));
    CHECK(f.narrow(1, kZ, 2 * kZ).abs().max().item<float>() == 0.0f);
    CHECK(torch::allclose(f.narrow(1, 0, kZ),
                          torch::relu(model->projections[0]->as<torch::nn::Linear>()->forward(
                              latents.select(1, 0)))));
  }
  {
    // HeMIS: one modality present: its embedding is the mean, variance 0;
    // none: all 0; camera and radar: mean and population variance of two.
    UavLocModel model(Config(FusionKind::kHemis));
    const int64_t d = HemisEmbedding(kZ);
    const torch::Tensor e0 =
        torch::relu(model->projections[0]->as<torch::nn::Linear>()->forward(latents.select(1, 0)));
    const torch::Tensor e2 =
        torch::relu(model->projections[2]->as<torch::nn::Linear>()->forward(latents.select(1, 2)));
    torch::Tensor f = model->Fuse(latents, camera_only);
    CHECK(torch::allclose(f.narrow(1, 0, d), e0));
    CHECK(f.narrow(1, d, d).abs().max().item<float>() == 0.0f);
    CHECK(model->Fuse(latents, none).abs().max().item<float>() == 0.0f);
    f = model->Fuse(latents, torch::tensor({1.0f, 0.0f, 1.0f}).repeat({4, 1}));
    CHECK(torch::allclose(f.narrow(1, 0, d), (e0 + e2) / 2, 1e-5, 1e-6));
    CHECK(torch::allclose(f.narrow(1, d, d), (e0 - e2).square() / 4, 1e-5, 1e-6));
  }
  {
    // Late fusion: with one modality present, its branch's position alone
    // (weight 1); with none, the centre (0 normalised).
    UavLocModel model(Config(FusionKind::kLate));
    const torch::Tensor seq = torch::randn({2, 5, 3, kZ});
    const torch::Tensor lidar_only = torch::tensor({0.0f, 1.0f, 0.0f}).repeat({2, 5, 1});
    const torch::Tensor branch =
        model->branches[1]->as<TemporalRegressor>()->forward(seq.select(2, 1));
    CHECK(torch::allclose(model(seq, lidar_only), branch, 1e-5, 1e-6));
    CHECK(model(seq, torch::zeros({2, 5, 3})).abs().max().item<float>() == 0.0f);
    // All three: the softmax of the learnable logits weighs the branches.
    model->late_logits.copy_(torch::tensor({0.0f, std::log(2.0f), std::log(5.0f)}));
    torch::Tensor sum = torch::zeros({2, 5, 3});
    const float w[3] = {1.0f / 8, 2.0f / 8, 5.0f / 8};
    for (int m = 0; m < 3; ++m)
      sum += w[m] * model->branches[static_cast<std::size_t>(m)]->as<TemporalRegressor>()->forward(
                        seq.select(2, m));
    CHECK(torch::allclose(model(seq, torch::ones({2, 5, 3})), sum, 1e-5, 1e-6));
  }
  {
    // MADW and MICA off: the masked latents, concatenated.
    UavLocModel model(Config(FusionKind::kUavLoc, false, false));
    CHECK(torch::equal(model->Fuse(latents, camera_only),
                       (latents * camera_only.unsqueeze(-1)).flatten(1)));
    CHECK(model->madw.is_empty());
    CHECK(model->mica.is_empty());
  }
}

TEST_CASE("Fusion variants: the online Step equals the batch forward; save and load",
          "[pipeline]") {
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(11);
  for (const UavLocModelConfig& config : AllKinds()) {
    INFO(Name(config));
    InitTorch(1, 13);
    UavLocModel model(config);
    std::vector<AlignedWindow> aligned;
    std::vector<Eigen::Vector3d> online;
    for (std::int64_t k = 1; k <= 30; ++k) {
      WindowInputs w;
      w.window = k;
      for (int m = 0; m < 3; ++m) {
        if (torch::rand({1}, gen).item<double>() < 0.3) continue;
        const torch::Tensor t = torch::randn({kZ}, gen);
        w.frames[static_cast<std::size_t>(m)].push_back(
            {(k - 0.5) * 0.2,
             std::vector<float>(t.data_ptr<float>(), t.data_ptr<float>() + kZ),
             {}});
      }
      aligned.push_back(model->te_align().Align(w));
      online.push_back(model->Step(w));
    }
    const FusionBatch batch = StackWindows({aligned});
    torch::NoGradGuard no_grad;
    const torch::Tensor y = model->PositionInMetres(model(batch.latents, batch.mask));
    double worst = 0.0;
    for (std::int64_t k = 0; k < 30; ++k)
      for (int i = 0; i < 3; ++i)
        worst = std::max(
            worst, std::abs(y[0][k][i].item<double>() - online[static_cast<std::size_t>(k)][i]));
    CHECK(worst < 1e-5);

    const std::string path = testing::TempDir("fusion-variants") + "/edge.pt";
    SaveUavLocModel(model, path);
    UavLocModel loaded = LoadUavLocModel(path);
    CHECK(loaded->config().fusion == config.fusion);
    CHECK(loaded->config().madw == config.madw);
    CHECK(loaded->config().mica == config.mica);
    CHECK(torch::equal(loaded(batch.latents, batch.mask), model(batch.latents, batch.mask)));
  }
}

TEST_CASE("Fusion variants: baselines refuse MADW/MICA switches and the anchored head",
          "[pipeline]") {
  UavLocModelConfig c = Config(FusionKind::kEarly, false, true);
  CHECK_THROWS_AS(c.Validate(), std::invalid_argument);
  c = Config(FusionKind::kHemis);
  c.anchored = true;
  CHECK_THROWS_AS(c.Validate(), std::invalid_argument);
}

}  // namespace uavsim::pipeline
