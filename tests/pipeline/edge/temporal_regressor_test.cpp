// The temporal regressors (paper Sec. VI, Fig. 11: Mamba against GRU, LSTM
// and TCN with the fusion unchanged): shapes, the online step against the
// whole sequence, causality, the TCN's receptive field worked by hand, equal
// sizes, a small fit, and models saved before the choice existed loading as
// the Mamba they are, weight for weight.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include "core/json_io.h"
#include "pipeline/edge/temporal_regressor.h"
#include "pipeline/edge/uavloc_model.h"
#include "pipeline/torch_runtime.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

const std::vector<TemporalKind> kKinds = {TemporalKind::kMamba, TemporalKind::kGru,
                                          TemporalKind::kLstm, TemporalKind::kTcn};

// A small regressor of `kind`, sized to a Mamba of d_model 16 (TCN kernel 3).
TemporalRegressorOptions Small(TemporalKind kind, int input_dim = 6, int output_dim = 3,
                               int layers = 2) {
  MambaRegressorOptions mamba;
  mamba.input_dim = input_dim;
  mamba.output_dim = output_dim;
  mamba.layers = layers;
  mamba.mamba.d_model = 16;
  return MatchedTemporalOptions(kind, mamba, 3);
}

void Perturb(torch::nn::Module& module) {
  torch::NoGradGuard no_grad;
  for (auto& p : module.parameters()) p.add_(torch::randn_like(p) * 0.1);
}

int64_t Numel(const torch::nn::Module& module) {
  int64_t n = 0;
  for (const auto& p : module.parameters()) n += p.numel();
  return n;
}

double MaxAbs(const torch::Tensor& t) { return t.abs().max().item<double>(); }

// The default model's Mamba regressor options, read from its sidecar by
// hand (not through UavLocModelConfig), for building one directly.
MambaRegressorOptions MambaOptionsOf(const core::Json& sidecar) {
  MambaRegressorOptions o;
  o.input_dim = 3 * sidecar.at("latent_dim").get<int>();
  o.output_dim = 3;
  o.layers = sidecar.at("layers").get<int>();
  o.mamba.d_model = sidecar.at("d_model").get<int>();
  o.mamba.d_state = sidecar.at("d_state").get<int>();
  o.mamba.d_conv = sidecar.at("d_conv").get<int>();
  o.mamba.expand = sidecar.at("expand").get<int>();
  return o;
}

const std::string kShippedEdge = std::string(UAVSIM_SOURCE_DIR) + "/models/default/uavloc.pt";

}  // namespace

TEST_CASE("TemporalRegressor: every kind's shapes, and stepping equals the whole sequence",
          "[pipeline]") {
  InitTorch(1, 41);
  for (const TemporalKind kind : kKinds) {
    INFO(TemporalKindName(kind));
    TemporalRegressor regressor(Small(kind));
    CHECK(regressor->kind() == kind);
    Perturb(*regressor);
    const int64_t length = 37;
    const torch::Tensor x = torch::randn({2, length + 5, 6});
    torch::NoGradGuard no_grad;
    TemporalState final_state;
    const torch::Tensor whole = regressor->forward(x.slice(1, 0, length), &final_state);
    CHECK(whole.sizes() == torch::IntArrayRef({2, length, 3}));

    TemporalState state = regressor->InitialState(2);
    double worst = 0.0;
    for (int64_t t = 0; t < length; ++t) {
      const torch::Tensor y = regressor->Step(x.select(1, t), &state);
      REQUIRE(y.sizes() == torch::IntArrayRef({2, 3}));
      worst = std::max(worst, MaxAbs(y - whole.select(1, t)));
    }
    CHECK(worst < 1e-5);
    // The whole sequence's final state continues it as the stepped one does.
    const torch::Tensor longer = regressor->forward(x);
    double continued = 0.0;
    for (int64_t t = length; t < length + 5; ++t)
      continued = std::max(
          continued, MaxAbs(regressor->Step(x.select(1, t), &final_state) - longer.select(1, t)));
    CHECK(continued < 1e-5);
    // The outputs are not all alike (the check above could not pass by a
    // constant output).
    CHECK(MaxAbs(whole.select(1, 1) - whole.select(1, 0)) > 1e-3);
  }
  // Wrong shapes and another kind's state are refused.
  TemporalRegressor gru(Small(TemporalKind::kGru));
  TemporalState mamba_state = TemporalRegressor(Small(TemporalKind::kMamba))->InitialState(1);
  CHECK_THROWS_WITH(gru->Step(torch::zeros({1, 6}), &mamba_state),
                    Catch::Contains("not a gru regressor's"));
  CHECK_THROWS_AS(gru->forward(torch::zeros({1, 4, 5})), c10::Error);
  CHECK_THROWS_AS(TemporalRegressor(Small(TemporalKind::kTcn))->forward(torch::zeros({4, 6})),
                  c10::Error);
}

TEST_CASE("TemporalRegressor: every kind is causal", "[pipeline]") {
  InitTorch(1, 42);
  for (const TemporalKind kind : kKinds) {
    INFO(TemporalKindName(kind));
    TemporalRegressor regressor(Small(kind));
    Perturb(*regressor);
    torch::NoGradGuard no_grad;
    const int64_t length = 30, changed = 17;
    const torch::Tensor x = torch::randn({1, length, 6});
    torch::Tensor other = x.clone();
    other.select(1, changed).add_(torch::randn({1, 6}));
    const torch::Tensor a = regressor(x), b = regressor(other);
    CHECK(MaxAbs(a.slice(1, 0, changed) - b.slice(1, 0, changed)) < 1e-6);
    CHECK(MaxAbs(a.select(1, changed) - b.select(1, changed)) > 1e-4);
    CHECK(MaxAbs(a.select(1, changed + 1) - b.select(1, changed + 1)) > 1e-4);
  }
}

TEST_CASE("TcnRegressor: the receptive field from the kernel and the dilations", "[pipeline]") {
  InitTorch(1, 43);
  TcnRegressorOptions o;
  o.input_dim = 5;
  o.width = 12;
  o.layers = 3;
  o.kernel = 3;
  // By hand: blocks dilated 1, 2, 4, two convs each reaching (k - 1) d
  // windows back: 2 (2 + 4 + 8) = 28 back, so 29 windows.
  int64_t back = 0;
  for (const int dilation : {1, 2, 4}) back += 2 * (o.kernel - 1) * dilation;
  REQUIRE(back == 28);
  CHECK(o.receptive_field() == back + 1);

  TcnRegressor tcn(o);
  Perturb(*tcn);
  torch::NoGradGuard no_grad;
  const int64_t at = 40;
  const torch::Tensor x = torch::randn({1, at + 1, 5});
  const torch::Tensor y = tcn(x).select(1, at);
  const auto output_with_change_at = [&](int64_t t) {
    torch::Tensor other = x.clone();
    other.select(1, t).add_(torch::randn({1, 5}) * 3.0);
    return tcn(other).select(1, at);
  };
  // The output at `at` sees input at - 28 and not at - 29.
  CHECK(MaxAbs(output_with_change_at(at - back) - y) > 1e-5);
  CHECK(MaxAbs(output_with_change_at(at - back - 1) - y) < 1e-7);
  CHECK(MaxAbs(output_with_change_at(at - back - 5) - y) < 1e-7);

  // The online state: each conv keeps its last (k - 1) d inputs.
  const TcnState state = tcn->InitialState(2);
  REQUIRE(state.inputs.size() == 6);
  const int64_t expected[] = {2, 2, 4, 4, 8, 8};
  for (std::size_t i = 0; i < 6; ++i)
    CHECK(state.inputs[i].sizes() == torch::IntArrayRef({2, 12, expected[i]}));
}

TEST_CASE("TemporalRegressor: GRU, LSTM and TCN within 10 % of the Mamba's parameters",
          "[pipeline]") {
  // The default configuration: 3 modalities x z 16 in, 3 out, d_model 64,
  // 2 layers, d_state 16, d_conv 4, expand 2.
  UavLocModelConfig config;
  REQUIRE(config.latent_dim == 16);
  REQUIRE(config.d_model == 64);
  REQUIRE(config.layers == 2);
  InitTorch(1, 44);
  config.temporal = TemporalKind::kMamba;
  const int64_t mamba = Numel(*UavLocModel(config)->regressor);
  // The Mamba as MambaRegressor counts it, not through the wrapper.
  CHECK(mamba == Numel(*MambaRegressor(config.regressor().mamba)));
  CHECK(ParameterCount(config.regressor()) == mamba);
  for (const TemporalKind kind : {TemporalKind::kGru, TemporalKind::kLstm, TemporalKind::kTcn}) {
    config.temporal = kind;
    const TemporalRegressorOptions options = config.regressor();
    const int64_t count = Numel(*UavLocModel(config)->regressor);
    INFO(TemporalKindName(kind) << ": " << count << " parameters against the Mamba's " << mamba);
    CHECK(std::abs(static_cast<double>(count) / static_cast<double>(mamba) - 1.0) <= 0.10);
    CHECK(ParameterCount(options) == count);
  }
}

TEST_CASE("MatchedTemporalOptions: the width whose count is nearest, counted as the modules are",
          "[pipeline]") {
  InitTorch(1, 45);
  // Other sizes than the default, anchored-sized input and output too.
  for (const auto& [d_model, layers, input_dim, output_dim] :
       std::vector<std::tuple<int, int, int, int>>{{32, 3, 24, 3}, {48, 1, 102, 15}}) {
    MambaRegressorOptions mamba;
    mamba.input_dim = input_dim;
    mamba.output_dim = output_dim;
    mamba.layers = layers;
    mamba.mamba.d_model = d_model;
    CHECK(ParameterCount(mamba) == Numel(*MambaRegressor(mamba)));
    for (const TemporalKind kind : {TemporalKind::kGru, TemporalKind::kLstm, TemporalKind::kTcn}) {
      INFO(TemporalKindName(kind) << " at d_model " << d_model);
      const TemporalRegressorOptions o = MatchedTemporalOptions(kind, mamba, 4);
      CHECK(o.input_dim() == input_dim);
      CHECK(o.output_dim() == output_dim);
      const int64_t count = Numel(*TemporalRegressor(o));
      CHECK(ParameterCount(o) == count);
      // One unit wider or narrower is no nearer.
      const int width = kind == TemporalKind::kTcn ? o.tcn.width : o.recurrent.width;
      for (const int other : {width - 1, width + 1}) {
        TemporalRegressorOptions c = o;
        c.tcn.width = c.recurrent.width = other;
        CHECK(std::abs(ParameterCount(c) - ParameterCount(mamba)) >=
              std::abs(count - ParameterCount(mamba)));
      }
    }
  }
}

TEST_CASE("TemporalRegressor: a short fit of a toy sequence task lowers the loss tenfold",
          "[pipeline]") {
  for (const TemporalKind kind : kKinds) {
    INFO(TemporalKindName(kind));
    InitTorch(1, 46);
    TemporalRegressor regressor(Small(kind, 4, 2, 1));
    // y(t) = (x_0(t) - x_1(t), x_2(t - 1) + 0.5 x_3(t - 2)): needs the
    // present and two earlier steps.
    const torch::Tensor x = torch::randn({8, 24, 4});
    const torch::Tensor past1 = torch::constant_pad_nd(x, {0, 0, 1, 0}).slice(1, 0, 24);
    const torch::Tensor past2 = torch::constant_pad_nd(x, {0, 0, 2, 0}).slice(1, 0, 24);
    const torch::Tensor y = torch::stack(
        {x.select(2, 0) - x.select(2, 1), past1.select(2, 2) + 0.5 * past2.select(2, 3)}, 2);
    torch::optim::Adam adam(regressor->parameters(), torch::optim::AdamOptions(1e-2));
    double first = 0.0, last = 0.0;
    for (int step = 0; step < 400; ++step) {
      adam.zero_grad();
      const torch::Tensor loss = torch::mse_loss(regressor(x), y);
      if (step == 0) first = loss.item<double>();
      last = loss.item<double>();
      loss.backward();
      adam.step();
    }
    INFO("loss " << first << " -> " << last);
    CHECK(last < first / 10.0);
  }
}

TEST_CASE("UavLocModel: a sidecar without \"temporal\" loads as the Mamba, weight for weight",
          "[pipeline]") {
  InitTorch(1, 47);
  // The shipped model as a model saved before the choice existed: its
  // sidecar without the key (the weights are the Mamba's either way).
  core::Json sidecar = core::LoadJsonFile(SidecarPath(kShippedEdge));
  REQUIRE(sidecar.value("temporal", std::string("mamba")) == "mamba");
  sidecar.erase("temporal");
  const std::string old_edge = testing::TempDir("temporal_old_sidecar") + "/uavloc.pt";
  std::filesystem::copy_file(kShippedEdge, old_edge,
                             std::filesystem::copy_options::overwrite_existing);
  std::ofstream(SidecarPath(old_edge)) << sidecar.dump(2);
  UavLocModel model = LoadUavLocModel(old_edge);
  REQUIRE(model->config().temporal == TemporalKind::kMamba);
  REQUIRE(model->regressor->kind() == TemporalKind::kMamba);
  REQUIRE_FALSE(model->regressor->mamba.is_empty());

  // The same weights read straight into a MambaRegressor from the archive's
  // "regressor".
  MambaRegressor direct(MambaOptionsOf(sidecar));
  {
    torch::serialize::InputArchive archive, part;
    archive.load_from(kShippedEdge);
    REQUIRE(archive.try_read("regressor", part));
    direct->load(part);
  }
  const auto ours = model->regressor->named_parameters();
  const auto theirs = direct->named_parameters();
  REQUIRE(ours.size() == theirs.size());
  for (const auto& p : theirs) {
    INFO(p.key());
    REQUIRE(ours.contains(p.key()));
    CHECK(torch::equal(ours[p.key()], p.value()));
  }
  // And the model as a whole holds the regressor under the old names.
  const auto all = model->named_parameters();
  for (const auto& p : theirs) CHECK(all.contains("regressor." + p.key()));

  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::randn({2, 25, 48});
  CHECK(torch::equal(model->regressor(x), direct(x)));
  TemporalState state = model->regressor->InitialState(2);
  MambaRegressorState direct_state = direct->InitialState(2);
  for (int64_t t = 0; t < 5; ++t)
    CHECK(torch::equal(model->regressor->Step(x.select(1, t), &state),
                       direct->Step(x.select(1, t), &direct_state)));

  // Written now, a Mamba's sidecar names it; the weights are read back alike.
  const std::string dir = testing::TempDir("temporal_mamba");
  SaveUavLocModel(model, dir + "/uavloc.pt");
  CHECK_THAT(testing::ReadFile(SidecarPath(dir + "/uavloc.pt")),
             Catch::Contains("\"temporal\": \"mamba\""));
  UavLocModel again = LoadUavLocModel(dir + "/uavloc.pt");
  CHECK(torch::equal(again->regressor(x), direct(x)));
}

TEST_CASE("UavLocModel: a Mamba model draws the weights it drew before the choice existed",
          "[pipeline]") {
  UavLocModelConfig config;
  config.latent_dim = 8;
  config.d_model = 32;
  InitTorch(1, 48);
  UavLocModel model(config);
  // What UavLocModelImpl registered before: madw, mica, then the
  // MambaRegressor itself, in this order from the same seed.
  InitTorch(1, 48);
  Madw madw(kModalityCount, config.latent_dim, config.score_hidden);
  Mica mica(kModalityCount, config.latent_dim, config.score_hidden, config.lambda_init);
  MambaRegressorOptions o;
  o.input_dim = kModalityCount * config.latent_dim;
  o.mamba.d_model = config.d_model;
  MambaRegressor mamba(o);
  const auto ours = model->regressor->named_parameters();
  const auto theirs = mamba->named_parameters();
  REQUIRE(ours.size() == theirs.size());
  for (const auto& p : theirs) CHECK(torch::equal(ours[p.key()], p.value()));
}

TEST_CASE("UavLocModel: GRU, LSTM and TCN models step online as the batch, and save and load",
          "[pipeline]") {
  const std::string dir = testing::TempDir("temporal_models");
  for (const TemporalKind kind : {TemporalKind::kGru, TemporalKind::kLstm, TemporalKind::kTcn}) {
    INFO(TemporalKindName(kind));
    InitTorch(1, 49);
    UavLocModelConfig config;
    config.latent_dim = 8;
    config.d_model = 32;
    config.temporal = kind;
    config.position_scale_m = 20.0;
    UavLocModel model(config);
    model->eval();
    torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(3);
    std::vector<WindowInputs> windows;
    std::vector<AlignedWindow> aligned;
    std::vector<Eigen::Vector3d> online;
    for (std::int64_t k = 1; k <= 40; ++k) {
      WindowInputs w;
      w.window = k;
      for (int m = 0; m < kModalityCount; ++m) {
        LatentFrame f;
        f.t_s = (k - 1) * 0.2 + 0.05 * (m + 1);
        const torch::Tensor t = torch::randn({8}, gen);
        f.latent.assign(t.data_ptr<float>(), t.data_ptr<float>() + 8);
        w.frames[static_cast<std::size_t>(m)].push_back(f);
      }
      windows.push_back(w);
      aligned.push_back(model->te_align().Align(w));
      online.push_back(model->Step(w));
    }
    const FusionBatch batch = StackWindows({aligned});
    torch::NoGradGuard no_grad;
    const torch::Tensor metres = model->PositionInMetres(model(batch.latents, batch.mask));
    double worst = 0.0;
    for (std::int64_t k = 0; k < 40; ++k)
      for (int i = 0; i < 3; ++i)
        worst = std::max(worst, std::abs(metres[0][k][i].item<double>() -
                                         online[static_cast<std::size_t>(k)][i]));
    CHECK(worst < 1e-5 * 20.0);  // 1e-5 in normalised units

    const std::string path = dir + "/" + TemporalKindName(kind) + ".pt";
    SaveUavLocModel(model, path);
    CHECK_THAT(testing::ReadFile(SidecarPath(path)),
               Catch::Contains("\"temporal\": \"" + std::string(TemporalKindName(kind)) + "\""));
    UavLocModel loaded = LoadUavLocModel(path);
    loaded->eval();
    CHECK(loaded->regressor->kind() == kind);
    const auto a = model->named_parameters();
    const auto b = loaded->named_parameters();
    REQUIRE(a.size() == b.size());
    for (const auto& p : a) CHECK(torch::equal(p.value(), b[p.key()]));
    model->ResetState();
    for (std::size_t k = 0; k < 5; ++k) CHECK(model->Step(windows[k]) == loaded->Step(windows[k]));
  }
  // A kind nobody knows is refused with the sidecar's key and the choices.
  const std::string path = dir + "/gru.pt";
  core::Json sidecar = core::LoadJsonFile(SidecarPath(path));
  sidecar["temporal"] = "rnn";
  testing::WriteFile(SidecarPath(path), sidecar.dump(2));
  CHECK_THROWS_WITH(
      LoadUavLocModel(path),
      Catch::Contains("/temporal") && Catch::Contains("\"mamba\", \"gru\", \"lstm\", \"tcn\""));
}

}  // namespace uavsim::pipeline
