// The UAVLoc edge network end to end (paper Sec. V): shapes, all-missing
// windows without NaN, the online step against the batch forward, a small
// training run, save/load, determinism and the torch-free facade.
#include <torch/torch.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/json_io.h"
#include "pipeline/edge/edge_localizer.h"
#include "pipeline/edge/uavloc_model.h"
#include "pipeline/torch_runtime.h"
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

UavLocModelConfig AnchoredConfig(int z = 8) {
  UavLocModelConfig c = SmallConfig(z);
  c.anchored = true;
  return c;
}

// Anchors of B sequences of K windows as StackAnchors lays them out: random
// features and candidates, each candidate valid with probability p_valid.
AnchorBatch RandomAnchors(int64_t b, int64_t k, double p_valid) {
  AnchorBatch a;
  a.features = torch::randn({b, k, kAnchorFeatures});
  a.candidates = torch::randn({b, k, kAnchorCandidates, 3});
  a.valid = torch::bernoulli(torch::full({b, k, kAnchorCandidates}, p_valid));
  // A held ray (valid, origin, unit direction) in about half the windows.
  const torch::Tensor direction = torch::randn({b, k, 3});
  a.ray = torch::cat({torch::bernoulli(torch::full({b, k, 1}, 0.5)), torch::randn({b, k, 3}),
                      direction / direction.norm(2, -1, true)},
                     -1);
  return a;
}

AnchorBatch Clone(const AnchorBatch& a) {
  return {a.features.clone(), a.candidates.clone(), a.valid.clone(), a.ray.clone()};
}

Eigen::Vector3d RandomVector(torch::Generator& gen) {
  const torch::Tensor t = torch::randn({3}, gen).to(torch::kFloat64);
  return {t[0].item<double>(), t[1].item<double>(), t[2].item<double>()};
}

// RandomWindow whose frames carry anchors around `centre_m` (spread `spread_m`):
// camera frames a ray (none, as if nothing was detected, with probability
// 0.2), LiDAR and radar frames a point.
WindowInputs RandomAnchoredWindow(std::int64_t k, int z, double drop,
                                  const Eigen::Vector3d& centre_m, double spread_m,
                                  torch::Generator& gen) {
  WindowInputs w = RandomWindow(k, z, drop, gen);
  // A target per window; rays towards it, points near it (most of them
  // within the tracker's gates), some far off.
  const Eigen::Vector3d target = centre_m + spread_m * RandomVector(gen);
  for (int m = 0; m < kModalityCount; ++m)
    for (LatentFrame& f : w.frames[static_cast<std::size_t>(m)]) {
      f.anchor.t_s = f.t_s;
      if (m == static_cast<int>(Modality::kCamera)) {
        if (torch::rand({1}, gen).item<double>() < 0.2) continue;
        f.anchor.kind = GeometricAnchor::Kind::kRay;
        f.anchor.origin_w = centre_m + 2.0 * spread_m * RandomVector(gen);
        f.anchor.direction_w = (target - f.anchor.origin_w).normalized();
      } else {
        const double off = torch::rand({1}, gen).item<double>() < 0.8 ? 0.3 : spread_m;
        f.anchor.kind = GeometricAnchor::Kind::kPoint;
        f.anchor.origin_w = target + off * RandomVector(gen);
        f.anchor.sensor_w = centre_m + spread_m * RandomVector(gen);
        f.anchor.range_m = (f.anchor.origin_w - f.anchor.sensor_w).norm();
      }
    }
  return w;
}

// Twenty windows with nothing at all step to finite positions.
void CheckEmptyStepsFinite(UavLocModel& model) {
  WindowInputs empty;
  for (std::int64_t k = 1; k <= 20; ++k) {
    empty.window = k;
    CHECK(model->Step(empty).allFinite());
  }
}

// The head's raw output [B, K, C + 6] for the given inputs, the way an
// anchored forward feeds the regressor: [t^f, anchor features].
torch::Tensor HeadOutput(UavLocModel& model, const torch::Tensor& latents,
                         const torch::Tensor& mask, const AnchorBatch& anchors) {
  const int64_t b = latents.size(0), k = latents.size(1), z = latents.size(3);
  const torch::Tensor fused =
      model
          ->Fuse(latents.reshape({b * k, kModalityCount, z}), mask.reshape({b * k, kModalityCount}))
          .reshape({b, k, kModalityCount * z});
  return model->regressor(torch::cat({fused, anchors.features}, 2));
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
  CheckEmptyStepsFinite(model);
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

TEST_CASE("UavLocModel anchored: shapes, and forward needs the anchors", "[pipeline]") {
  InitTorch(1, 31);
  UavLocModel model(AnchoredConfig(8));
  CHECK(model->regressor->embed->weight.sizes() ==
        torch::IntArrayRef({32, 3 * 8 + kAnchorFeatures}));
  CHECK(model->regressor->head->weight.sizes() ==
        torch::IntArrayRef({UavLocModelImpl::kHypotheses + 4, 32}));
  const torch::Tensor latents = torch::randn({4, 10, 3, 8});
  const torch::Tensor mask = torch::bernoulli(torch::full({4, 10, 3}, 0.7));
  const AnchorBatch anchors = RandomAnchors(4, 10, 0.5);
  CHECK(model(latents, mask, &anchors).sizes() == torch::IntArrayRef({4, 10, 3}));
  CHECK_THROWS_AS(model(latents, mask), c10::Error);
  CHECK_THROWS_AS(model->forward(latents, mask, nullptr), c10::Error);
  AnchorBatch short_features = Clone(anchors);
  short_features.features = short_features.features.narrow(2, 0, kAnchorFeatures - 1);
  CHECK_THROWS_AS(model(latents, mask, &short_features), c10::Error);
  const AnchorBatch fewer_windows = RandomAnchors(4, 9, 0.5);
  CHECK_THROWS_AS(model(latents, mask, &fewer_windows), c10::Error);

  // A plain model ignores anchors.
  UavLocModel plain(SmallConfig(8));
  CHECK(torch::equal(plain(latents, mask, &anchors), plain(latents, mask)));
}

TEST_CASE("UavLocModel anchored: the output is the softmax mix of the valid candidates",
          "[pipeline]") {
  InitTorch(1, 32);
  UavLocModel model(AnchoredConfig(8));
  torch::NoGradGuard no_grad;
  const int64_t b = 3, k = 7, c = kAnchorCandidates;
  const torch::Tensor latents = torch::randn({b, k, 3, 8});
  const torch::Tensor mask = torch::bernoulli(torch::full({b, k, 3}, 0.7));
  AnchorBatch anchors = RandomAnchors(b, k, 0.5);
  anchors.valid[0][0].fill_(1.0f);  // one window with every candidate,
  anchors.valid[0][1].fill_(0.0f);  // one with none
  const torch::Tensor out = model(latents, mask, &anchors);
  const torch::Tensor head = HeadOutput(model, latents, mask, anchors).to(torch::kFloat64);
  const int64_t h = UavLocModelImpl::kHypotheses;
  REQUIRE(h == c + 2);
  REQUIRE(head.sizes() == torch::IntArrayRef({b, k, h + 4}));
  // w = softmax of l = head[0:c + 2] over the valid candidates, the ray's
  // point f = o + softplus(head[c + 5]) d (where a ray is held) and the
  // absolute a = head[c + 2:c + 5] (always); p = sum_i w_i c_i + w_f f +
  // w_a a. Log-weights: -inf for what is not allowed.
  torch::Tensor log_w;
  model->forward(latents, mask, &anchors, &log_w);
  REQUIRE(log_w.sizes() == torch::IntArrayRef({b, k, h}));
  double worst = 0.0, worst_log = 0.0;
  int with_ray = 0;
  for (int64_t s = 0; s < b; ++s)
    for (int64_t w = 0; w < k; ++w) {
      const bool ray = anchors.ray[s][w][0].item<float>() > 0.5f;
      with_ray += ray ? 1 : 0;
      const double t = std::log1p(std::exp(head[s][w][c + 5].item<double>()));
      std::vector<Eigen::Vector3d> position(static_cast<std::size_t>(h));
      std::vector<bool> allowed(static_cast<std::size_t>(h), true);
      for (int64_t i = 0; i < c; ++i) {
        allowed[static_cast<std::size_t>(i)] = anchors.valid[s][w][i].item<float>() > 0.5f;
        for (int j = 0; j < 3; ++j)
          position[static_cast<std::size_t>(i)][j] = anchors.candidates[s][w][i][j].item<double>();
      }
      allowed[static_cast<std::size_t>(c)] = ray;
      for (int j = 0; j < 3; ++j) {
        position[static_cast<std::size_t>(c)][j] =
            anchors.ray[s][w][1 + j].item<double>() + t * anchors.ray[s][w][4 + j].item<double>();
        position[static_cast<std::size_t>(c + 1)][j] = head[s][w][c + 2 + j].item<double>();
      }
      double total = 0.0;
      for (int64_t i = 0; i < h; ++i)
        if (allowed[static_cast<std::size_t>(i)]) total += std::exp(head[s][w][i].item<double>());
      Eigen::Vector3d expected = Eigen::Vector3d::Zero();
      for (int64_t i = 0; i < h; ++i) {
        const double got = log_w[s][w][i].item<double>();
        if (!allowed[static_cast<std::size_t>(i)]) {
          CHECK(std::isinf(got));
          CHECK(got < 0.0);
          continue;
        }
        const double weight = std::exp(head[s][w][i].item<double>()) / total;
        worst_log = std::max(worst_log, std::abs(got - std::log(weight)));
        expected += weight * position[static_cast<std::size_t>(i)];
      }
      for (int j = 0; j < 3; ++j)
        worst = std::max(worst, std::abs(out[s][w][j].item<double>() - expected[j]));
    }
  REQUIRE(with_ray >= 1);
  REQUIRE(with_ray < b * k);
  CHECK(worst < 1e-5);
  CHECK(worst_log < 1e-5);

  // The hypotheses those weights weigh: the candidates, the ray's point, a.
  torch::Tensor hypotheses;
  model->forward(latents, mask, &anchors, nullptr, &hypotheses);
  REQUIRE(hypotheses.sizes() == torch::IntArrayRef({b, k, h, 3}));
  CHECK(torch::equal(hypotheses.narrow(2, 0, c), anchors.candidates));
  CHECK(torch::allclose(hypotheses.select(2, c + 1).to(torch::kFloat64), head.narrow(-1, c + 2, 3),
                        0.0, 1e-6));
}

TEST_CASE("UavLocModel anchored: calibrated candidate offsets are subtracted from the candidates",
          "[pipeline]") {
  UavLocModelConfig config = AnchoredConfig(8);
  config.position_scale_m = 20.0;
  UavLocModelConfig calibrated = config;
  for (int i = 0; i < kAnchorCandidates; ++i)
    calibrated.candidate_offset_m.emplace_back(0.01 * i, -0.02 * i, 0.03 + 0.1 * (i == 6));
  InitTorch(1, 40);
  UavLocModel plain(config);
  InitTorch(1, 40);
  UavLocModel model(calibrated);
  torch::NoGradGuard no_grad;
  const int64_t b = 2, k = 6, c = kAnchorCandidates;
  const torch::Tensor latents = torch::randn({b, k, 3, 8});
  const torch::Tensor mask = torch::bernoulli(torch::full({b, k, 3}, 0.7));
  const AnchorBatch anchors = RandomAnchors(b, k, 0.6);
  torch::Tensor log_w, hypotheses, plain_log_w;
  const torch::Tensor out = model->forward(latents, mask, &anchors, &log_w, &hypotheses);
  const torch::Tensor plain_out = plain->forward(latents, mask, &anchors, &plain_log_w);
  // The weights do not change (the features are the uncorrected ones); each
  // candidate hypothesis moves by -offset / scale, so the output by the
  // weighted sum of that.
  CHECK(torch::equal(log_w, plain_log_w));
  double worst_h = 0.0, worst_out = 0.0;
  for (int64_t s = 0; s < b; ++s)
    for (int64_t w = 0; w < k; ++w) {
      Eigen::Vector3d shift = Eigen::Vector3d::Zero();
      for (int64_t i = 0; i < c; ++i) {
        const Eigen::Vector3d o = calibrated.candidate_offset_m[static_cast<std::size_t>(i)] / 20.0;
        for (int j = 0; j < 3; ++j)
          worst_h =
              std::max(worst_h, std::abs(hypotheses[s][w][i][j].item<double>() -
                                         (anchors.candidates[s][w][i][j].item<double>() - o[j])));
        shift -= std::exp(log_w[s][w][i].item<double>()) * o;
      }
      for (int j = 0; j < 3; ++j)
        worst_out = std::max(worst_out, std::abs(out[s][w][j].item<double>() -
                                                 (plain_out[s][w][j].item<double>() + shift[j])));
    }
  CHECK(worst_h < 1e-6);
  CHECK(worst_out < 1e-6);

  // The offsets round-trip through the sidecar, which refuses a wrong count
  // or an offset beyond kMaxCandidateOffset_m, naming the JSON pointer.
  const std::string dir = testing::TempDir("fusion_model_offsets");
  const std::string path = dir + "/uavloc.pt";
  SaveUavLocModel(model, path);
  UavLocModel loaded = LoadUavLocModel(path);
  REQUIRE(loaded->config().candidate_offset_m.size() == static_cast<std::size_t>(c));
  for (std::size_t i = 0; i < static_cast<std::size_t>(c); ++i)
    CHECK(loaded->config().candidate_offset_m[i] == calibrated.candidate_offset_m[i]);
  const std::string sidecar = testing::ReadFile(SidecarPath(path));
  core::Json j = core::Json::parse(sidecar);
  j["candidate_offset_m"][6][2] = 1.5;
  testing::WriteFile(SidecarPath(path), j.dump(2));
  CHECK_THROWS_WITH(LoadUavLocModel(path), Catch::Contains(SidecarPath(path)) &&
                                               Catch::Contains("/candidate_offset_m/6/2"));
  j = core::Json::parse(sidecar);
  j["candidate_offset_m"].erase(6);
  testing::WriteFile(SidecarPath(path), j.dump(2));
  CHECK_THROWS_WITH(LoadUavLocModel(path), Catch::Contains(SidecarPath(path)) &&
                                               Catch::Contains("/candidate_offset_m") &&
                                               Catch::Contains("got 6"));
  calibrated.candidate_offset_m.pop_back();
  CHECK_THROWS_AS(UavLocModel(calibrated), std::invalid_argument);
}

TEST_CASE("UavLocModel anchored: invalid candidates have no influence, valid ones do",
          "[pipeline]") {
  InitTorch(1, 33);
  UavLocModel model(AnchoredConfig(8));
  torch::NoGradGuard no_grad;
  const int64_t b = 3, k = 9;
  const torch::Tensor latents = torch::randn({b, k, 3, 8});
  const torch::Tensor mask = torch::bernoulli(torch::full({b, k, 3}, 0.7));
  AnchorBatch zeros = RandomAnchors(b, k, 0.5);
  zeros.valid[1][4].copy_(
      torch::tensor({1.0f, 0.0f, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f}));  // both kinds below
  AnchorBatch huge = Clone(zeros);
  const torch::Tensor invalid = (zeros.valid < 0.5).unsqueeze(-1).expand_as(zeros.candidates);
  zeros.candidates.masked_fill_(invalid, 0.0f);
  huge.candidates.masked_fill_(invalid, 1e6f);
  REQUIRE(invalid.any().item<bool>());
  const torch::Tensor out = model(latents, mask, &zeros);
  REQUIRE(AllFinite(out));
  CHECK(torch::equal(out, model(latents, mask, &huge)));

  // Moving a valid candidate moves that window's output, by less than the
  // candidate moved (its weight is in (0, 1)) and along the same direction;
  // the other windows do not change (candidates do not enter the state).
  AnchorBatch moved = Clone(zeros);
  moved.candidates[1][4][2] += torch::tensor({1.0f, -2.0f, 0.5f});
  const torch::Tensor moved_out = model(latents, mask, &moved);
  const torch::Tensor delta = (moved_out - out)[1][4];
  CHECK(delta.norm().item<double>() > 1e-4);
  CHECK(delta.norm().item<double>() < std::sqrt(5.25));
  const torch::Tensor ratio = delta / torch::tensor({1.0f, -2.0f, 0.5f});
  CHECK((ratio - ratio[0]).abs().max().item<double>() < 1e-5);
  CHECK(ratio[0].item<double>() > 0.0);
  CHECK(ratio[0].item<double>() < 1.0);
  torch::Tensor others = (moved_out - out).abs();
  others[1][4].zero_();
  CHECK(others.max().item<double>() == 0.0);

  // Moving an invalid one there changes nothing.
  AnchorBatch moved_invalid = Clone(zeros);
  moved_invalid.candidates[1][4][3] += torch::tensor({1.0f, -2.0f, 0.5f});
  CHECK(torch::equal(model(latents, mask, &moved_invalid), out));
}

TEST_CASE("UavLocModel anchored: no valid candidate leaves the free position, never NaN",
          "[pipeline]") {
  InitTorch(1, 34);
  UavLocModel model(AnchoredConfig(8));
  const int64_t b = 2, k = 12;
  const torch::Tensor latents = torch::randn({b, k, 3, 8});
  torch::Tensor mask = torch::ones({b, k, 3});
  mask.slice(1, 3, 9).zero_();  // six windows with nothing at all
  mask[1].zero_();              // a whole sequence with nothing at all
  AnchorBatch none = RandomAnchors(b, k, 0.0);
  none.features.zero_();  // what the tracker gives before anything is seen
  none.features.slice(2, 4 * kAnchorCandidates, 4 * kAnchorCandidates + 6).fill_(1.0f);
  none.ray.zero_();  // no ray held either
  REQUIRE(none.valid.sum().item<double>() == 0.0);
  {
    torch::NoGradGuard no_grad;
    const torch::Tensor out = model(latents, mask, &none);
    REQUIRE(AllFinite(out));
    CHECK(torch::equal(
        out, HeadOutput(model, latents, mask, none).narrow(-1, kAnchorCandidates + 2, 3)));
    AnchorBatch far = Clone(none);
    far.candidates.fill_(1e6f);
    CHECK(torch::equal(model(latents, mask, &far), out));
  }

  // Gradients through all-missing windows and all-invalid candidates.
  AnchorBatch some = RandomAnchors(b, k, 0.5);
  some.valid[0].zero_();
  for (const AnchorBatch* anchors : {&none, &some}) {
    model->zero_grad();
    const torch::Tensor out = model(latents, mask, anchors);
    REQUIRE(AllFinite(out));
    out.pow(2).sum().backward();
    for (const auto& p : model->named_parameters()) {
      INFO(p.key());
      if (p.value().grad().defined()) CHECK(AllFinite(p.value().grad()));
    }
  }

  model->eval();
  CheckEmptyStepsFinite(model);
}

TEST_CASE("UavLocModel anchored: the online Step equals the batch forward with tracked anchors",
          "[pipeline]") {
  InitTorch(1, 35);
  UavLocModelConfig config = AnchoredConfig(8);
  config.position_centre_m = {10.0, -5.0, 30.0};
  config.position_scale_m = 20.0;
  UavLocModel model(config);
  model->eval();
  WindowInputs empty_first;
  empty_first.window = 1;
  const Eigen::Vector3d fresh_empty = model->Step(empty_first);
  model->ResetState();
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(9);
  // Windows 20 to 22 and 41 never reach Step (skipped: stepped as empty
  // windows); the batch sees them as empty windows.
  const auto skipped = [](std::int64_t k) { return (k >= 20 && k <= 22) || k == 41; };
  const std::int64_t windows = 60;
  AnchorTracker tracker(config.window_s, config.position_centre_m, config.position_scale_m);
  std::vector<AlignedWindow> aligned;
  std::vector<AnchorWindow> anchors;
  std::vector<WindowInputs> inputs;
  std::vector<std::optional<Eigen::Vector3d>> online;
  int with_ray = 0;
  for (std::int64_t k = 1; k <= windows; ++k) {
    WindowInputs w = RandomAnchoredWindow(k, 8, 0.3, config.position_centre_m, 10.0, gen);
    if (skipped(k)) w = WindowInputs{k, {}};
    inputs.push_back(w);
    aligned.push_back(model->te_align().Align(w));
    anchors.push_back(tracker.Update(k, model->te_align().AnchorsOf(w)));
    with_ray += anchors.back().valid[2] > 0.5f ? 1 : 0;
    online.push_back(skipped(k) ? std::nullopt : std::optional(model->Step(w)));
  }
  REQUIRE(with_ray > windows / 2);  // the anchors matter in most windows
  const FusionBatch batch = StackWindows({aligned});
  const AnchorBatch anchor_batch = StackAnchors({anchors});
  REQUIRE(anchor_batch.features.sizes() == torch::IntArrayRef({1, windows, kAnchorFeatures}));
  REQUIRE(anchor_batch.candidates.sizes() ==
          torch::IntArrayRef({1, windows, kAnchorCandidates, 3}));
  REQUIRE(anchor_batch.valid.sizes() == torch::IntArrayRef({1, windows, kAnchorCandidates}));
  torch::NoGradGuard no_grad;
  const torch::Tensor metres =
      model->PositionInMetres(model(batch.latents, batch.mask, &anchor_batch));
  double worst = 0.0;
  for (std::int64_t k = 0; k < windows; ++k) {
    const auto& p = online[static_cast<std::size_t>(k)];
    if (!p) continue;
    for (int i = 0; i < 3; ++i)
      worst = std::max(worst, std::abs(metres[0][k][i].item<double>() - (*p)[i]));
  }
  CHECK(worst < 1e-5 * 20.0);  // 1e-5 in normalised units

  // A tracker that forgets between windows (the same arrivals, no holding)
  // gives other outputs: Step really holds anchors across windows.
  std::vector<AnchorWindow> unheld;
  for (std::int64_t k = 1; k <= windows; ++k) {
    AnchorTracker forgetful(config.window_s, config.position_centre_m, config.position_scale_m);
    unheld.push_back(
        forgetful.Update(k, model->te_align().AnchorsOf(inputs[static_cast<std::size_t>(k - 1)])));
  }
  const AnchorBatch unheld_batch = StackAnchors({unheld});
  CHECK(!torch::allclose(model(batch.latents, batch.mask, &unheld_batch),
                         model(batch.latents, batch.mask, &anchor_batch)));

  // A gap longer than kMaxGapWindows restarts from nothing, anchors included:
  // an empty window then gives what an empty first window gave a fresh model.
  WindowInputs after_gap;
  after_gap.window = windows + UavLocModelImpl::kMaxGapWindows + 2;
  CHECK((model->Step(after_gap) - fresh_empty).norm() < 1e-9);
  // So does ResetState.
  model->Step(
      RandomAnchoredWindow(after_gap.window + 1, 8, 0.0, config.position_centre_m, 10.0, gen));
  model->ResetState();
  CHECK((model->Step(empty_first) - fresh_empty).norm() < 1e-9);
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
  AnchorFilter track(AnchorFilter::Motion::kImm);
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

  // TE-Align's tau origin: written, read back, and a sidecar from before the
  // key existed (none written) loads with the window origin it was trained on.
  UavLocModelConfig clock = config;
  clock.tau_origin = TauOrigin::kClock;
  SaveUavLocModel(UavLocModel(clock), path);
  CHECK_THAT(testing::ReadFile(SidecarPath(path)), Catch::Contains("\"tau_origin\": \"clock\""));
  CHECK(LoadUavLocModel(path)->config().tau_origin == TauOrigin::kClock);
  core::Json old = core::Json::parse(testing::ReadFile(SidecarPath(path)));
  old.erase("tau_origin");
  testing::WriteFile(SidecarPath(path), old.dump(2));
  CHECK(LoadUavLocModel(path)->config().tau_origin == TauOrigin::kWindow);
}

TEST_CASE("UavLocModel anchored: save and load round trip keeps anchored", "[pipeline]") {
  InitTorch(1, 36);
  UavLocModelConfig config = AnchoredConfig(8);
  config.position_centre_m = {1.0, 2.0, 3.0};
  config.position_scale_m = 50.0;
  UavLocModel model(config);
  model->eval();
  const std::string dir = testing::TempDir("fusion_model_anchored");
  const std::string path = dir + "/uavloc.pt";
  SaveUavLocModel(model, path);
  CHECK_THAT(testing::ReadFile(SidecarPath(path)), Catch::Contains("\"anchored\": true"));
  UavLocModel loaded = LoadUavLocModel(path);
  loaded->eval();
  CHECK(loaded->config().anchored);
  CHECK(loaded->regressor->head->weight.sizes() ==
        torch::IntArrayRef({UavLocModelImpl::kHypotheses + 4, 32}));
  const auto a = model->named_parameters();
  const auto b = loaded->named_parameters();
  REQUIRE(a.size() == b.size());
  for (const auto& p : a) CHECK(torch::equal(p.value(), b[p.key()]));
  {
    torch::NoGradGuard no_grad;
    const torch::Tensor latents = torch::randn({2, 6, 3, 8});
    const torch::Tensor mask = torch::bernoulli(torch::full({2, 6, 3}, 0.7));
    const AnchorBatch anchors = RandomAnchors(2, 6, 0.5);
    CHECK(torch::equal(model(latents, mask, &anchors), loaded(latents, mask, &anchors)));
  }
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(11);
  for (std::int64_t k = 1; k <= 8; ++k) {
    const WindowInputs w = RandomAnchoredWindow(k, 8, 0.2, config.position_centre_m, 10.0, gen);
    CHECK(model->Step(w) == loaded->Step(w));
  }

  // A plain model's sidecar says so, and one written before the anchors
  // existed (no "anchored" key) loads as a plain model.
  UavLocModel plain(SmallConfig(8));
  const std::string plain_path = dir + "/plain.pt";
  SaveUavLocModel(plain, plain_path);
  std::string sidecar = testing::ReadFile(SidecarPath(plain_path));
  CHECK_THAT(sidecar, Catch::Contains("\"anchored\": false"));
  const std::size_t at = sidecar.find("\"anchored\": false,");
  REQUIRE(at != std::string::npos);
  sidecar.erase(at, std::string("\"anchored\": false,").size());
  testing::WriteFile(SidecarPath(plain_path), sidecar);
  CHECK(!LoadUavLocModel(plain_path)->config().anchored);

  // The weights of a plain model do not fit an anchored sidecar.
  testing::WriteFile(SidecarPath(plain_path), testing::ReadFile(SidecarPath(path)));
  CHECK_THROWS_WITH(LoadUavLocModel(plain_path), Catch::Contains(plain_path));

  // An anchored model of the first anchored head (no "anchor_features": 41
  // features, a residual) is refused with what to do, naming the sidecar.
  std::string old = testing::ReadFile(SidecarPath(path));
  const std::string key = "\"anchor_features\": " + std::to_string(kAnchorFeatures) + ",";
  const std::size_t key_at = old.find(key);
  REQUIRE(key_at != std::string::npos);
  old.erase(key_at, key.size());
  testing::WriteFile(SidecarPath(path), old);
  CHECK_THROWS_WITH(LoadUavLocModel(path), Catch::Contains(SidecarPath(path)) &&
                                               Catch::Contains("41 anchor features") &&
                                               Catch::Contains("uavsim train"));
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

TEST_CASE("EdgeLocalizer: waiting for a track, an anchored model answers from its first track",
          "[pipeline]") {
  InitTorch(1, 29);
  const auto waits = EdgeLocalizer::Create(8, 0.2, true);
  const auto answers = EdgeLocalizer::Create(8, 0.2, true);
  waits->WaitForTrack(true);
  // Windows 1-3: a camera ray along +x from the origin and a radar point 30
  // m off the ray (no track: it does not agree with the ray, and a radar
  // never starts one alone); window 4: a LiDAR point 0.3 m from the ray at
  // 20 m, 0.13 s before the window's end, which starts the anchor filter's
  // track with an unknown velocity (its sigma at the deadline above
  // kConfirmedSigma_m: sqrt(3 (0.15^2 + 6^2 0.13^2)) = 1.37 m); window 5: a
  // second, which confirms it.
  torch::Generator gen = torch::make_generator<torch::CPUGeneratorImpl>(9);
  const auto frame = [&](double t, const GeometricAnchor& a) {
    LatentFrame f;
    f.t_s = t;
    f.latent.resize(8);
    for (float& x : f.latent) x = static_cast<float>(torch::randn({1}, gen).item<double>());
    f.anchor = a;
    f.anchor.t_s = t;
    return f;
  };
  GeometricAnchor ray;
  ray.kind = GeometricAnchor::Kind::kRay;
  ray.direction_w = Eigen::Vector3d::UnitX();
  GeometricAnchor far;
  far.kind = GeometricAnchor::Kind::kPoint;
  far.origin_w = {20.0, 30.0, 0.0};
  far.range_m = far.origin_w.norm();
  GeometricAnchor near = far;
  near.origin_w = {20.0, 0.3, 0.0};
  near.range_m = near.origin_w.norm();
  AnchorFilter track(AnchorFilter::Motion::kImm);
  for (std::int64_t k = 1; k <= 5; ++k) {
    WindowInputs w;
    w.window = k;
    const double t = 0.2 * static_cast<double>(k) - 0.15;
    w.frames[static_cast<std::size_t>(Modality::kCamera)].push_back(frame(t, ray));
    w.frames[static_cast<std::size_t>(Modality::kRadar)].push_back(frame(t + 0.01, far));
    if (k >= 4)
      w.frames[static_cast<std::size_t>(Modality::kLidar)].push_back(frame(t + 0.02, near));
    INFO("window " << k);
    CHECK(answers->OnWindow(w).has_value());
    CHECK(waits->OnWindow(w).has_value() == (k == 5));
    // The track's sigma at the deadline, as the tracker's filter sees it.
    for (const Modality m : {Modality::kCamera, Modality::kRadar, Modality::kLidar})  // by t_s
      for (const LatentFrame& f : w.frames[static_cast<std::size_t>(m)]) track.Observe(m, f.anchor);
    const std::optional<AnchorFilter::Estimate> e = track.PredictAt(0.2 * static_cast<double>(k));
    CHECK(e.has_value() == (k >= 4));
    if (k == 4) CHECK(e->sigma_m == Approx(1.37).margin(0.01));
    if (k == 5) CHECK(e->sigma_m < EdgeLocalizer::kConfirmedSigma_m);
  }
  // The track once confirmed, the model answers on (the state carries it).
  WindowInputs empty;
  empty.window = 6;
  CHECK(waits->OnWindow(empty).has_value());
  // Reset forgets it.
  waits->Reset();
  empty.window = 1;
  CHECK_FALSE(waits->OnWindow(empty).has_value());
}

}  // namespace uavsim::pipeline
