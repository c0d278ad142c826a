// Saving and loading IB-CC models, and the torch-free NodeEncoder the engine
// calls at run time.
#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "pipeline/node/ib_encoder.h"
#include "pipeline/node/ib_model_io.h"
#include "pipeline/node/node_encoder.h"
#include "pipeline/torch_runtime.h"
#include "test_support.h"

namespace uavsim::pipeline {
namespace {

CameraObservation SomeCamera(float shade) {
  CameraObservation o;
  o.detected = true;
  o.crop_left.assign(128 * 128, shade);
  o.crop_right.assign(128 * 128, 1.0f - shade);
  for (int i = 0; i < 128; ++i) o.crop_left[static_cast<std::size_t>(i * 129)] = 1.0f;
  o.centre_left_px = {300.0f, 200.0f};
  o.centre_right_px = {280.0f, 201.0f};
  o.side_left_px = 40.0f;
  o.side_right_px = 38.0f;
  o.eye_left_w = {-30.0, -30.0, 1.5};
  o.eye_right_w = {-29.9, -30.0, 1.5};
  o.bearing_left_w = Eigen::Vector3d(1.0, 1.0, 1.0).normalized();
  o.bearing_right_w = Eigen::Vector3d(1.0, 1.1, 1.0).normalized();
  return o;
}

PointObservation SomeCloud(Modality m, int n, float offset) {
  PointObservation o;
  o.channels = PointChannels(m);
  for (int i = 0; i < n; ++i) {
    o.values.push_back(offset + 0.1f * static_cast<float>(i));
    o.values.push_back(2.0f - 0.05f * static_cast<float>(i));
    o.values.push_back(30.0f + 0.01f * static_cast<float>(i * i % 7));
    if (m == Modality::kLidar) {
      o.values.push_back(0.3f);
    } else {
      o.values.push_back(-4.0f + 0.2f * static_cast<float>(i));
      o.values.push_back(20.0f + static_cast<float>(i % 3));
    }
  }
  return o;
}

IbCcConfig Config(Modality m, int z) {
  IbCcConfig c;
  c.modality = m;
  c.latent_dim = z;
  c.normalization.centre_m = {1.0, 2.0, 25.0};
  c.normalization.scale_m = 20.0;
  c.normalization.image_width_px = 600.0;
  return c;
}

IbInput InputFor(Modality m, const IbNormalization& n) {
  static const CameraObservation cam_a = SomeCamera(0.2f), cam_b = SomeCamera(0.7f);
  static const PointObservation lidar_a = SomeCloud(Modality::kLidar, 12, 0.0f),
                                lidar_b = SomeCloud(Modality::kLidar, 30, 3.0f);
  static const PointObservation radar_a = SomeCloud(Modality::kRadar, 5, 1.0f),
                                radar_b = SomeCloud(Modality::kRadar, 9, -2.0f);
  if (m == Modality::kCamera) return MakeCameraInput({&cam_a, &cam_b}, n);
  if (m == Modality::kLidar) return MakePointInput({&lidar_a, &lidar_b}, m, n);
  return MakePointInput({&radar_a, &radar_b}, m, n);
}

}  // namespace

TEST_CASE("IbModelIo: save then load gives identical outputs", "[pipeline]") {
  InitTorch(1, 31);
  const std::string dir = testing::TempDir("ibcc-io");
  for (Modality m : {Modality::kCamera, Modality::kLidar, Modality::kRadar}) {
    const IbCcConfig config = Config(m, 8);
    IbCcModel model(config);
    const IbInput in = InputFor(m, config.normalization);
    {
      // A train-mode pass moves the BatchNorm running statistics off their
      // defaults, so the buffers are checked too.
      model->train();
      torch::NoGradGuard no_grad;
      model->forward(in);
    }
    model->eval();
    const std::string path = dir + "/" + ModalityName(m) + ".json";
    SaveIbCcModel(model, path, "test model");
    CHECK(std::filesystem::exists(dir + "/" + ModalityName(m) + ".pt"));

    IbCcModel loaded = LoadIbCcModel(path);
    CHECK_FALSE(loaded->is_training());
    torch::NoGradGuard no_grad;
    const IbOutput a = model->forward(in);
    const IbOutput b = loaded->forward(in);
    CHECK(torch::equal(a.mu, b.mu));
    CHECK(torch::equal(a.sigma, b.sigma));
    CHECK(torch::equal(a.y_hat, b.y_hat));

    const IbModelFile file = ReadIbCcSidecar(path);
    CHECK(file.weights == std::string(ModalityName(m)) + ".pt");
    CHECK(file.note == "test model");
    CHECK(file.config.modality == m);
    CHECK(file.config.latent_dim == 8);
    CHECK(file.config.normalization.centre_m == config.normalization.centre_m);
    CHECK(file.config.normalization.scale_m == 20.0);
    CHECK(file.config.normalization.image_width_px == 600.0);
    // torch::save names its archive's folder after the file it writes: the
    // final name, not a per-process temporary one, so that the same weights
    // give the same bytes in every run (the shipped model reproduces).
    const std::string weights = testing::ReadFile(dir + "/" + file.weights);
    const auto entry = weights.find(file.weights + "/data/");
    REQUIRE(entry != std::string::npos);
    CHECK(entry > 0);
    CHECK(weights[entry - 1] != '.');  // not ".lidar.pt/data/" (a hidden temporary's stem)
    CHECK(weights.find(".tmp-") == std::string::npos);
  }
  // No temp files left behind.
  for (const auto& e : std::filesystem::directory_iterator(dir))
    CHECK(e.path().string().find(".tmp-") == std::string::npos);
}

TEST_CASE("IbModelIo: bad sidecars and weights are named", "[pipeline]") {
  InitTorch(1, 32);
  const std::string dir = testing::TempDir("ibcc-io-bad");
  IbCcModel model(Config(Modality::kLidar, 16));
  SaveIbCcModel(model, dir + "/lidar.json");
  const std::string good = testing::ReadFile(dir + "/lidar.json");

  testing::WriteFile(dir + "/typo.json", R"({"format": "uavsim-ibcc/1", "weights": "lidar.pt",
    "config": {"modality": "lidar", "latent_dims": 16}})");
  CHECK_THAT(testing::ConfigErrorOf([&] { LoadIbCcModel(dir + "/typo.json"); }),
             Catch::Contains("/config/latent_dims") && Catch::Contains("latent_dim"));

  testing::WriteFile(dir + "/z.json", R"({"format": "uavsim-ibcc/1", "weights": "lidar.pt",
    "config": {"modality": "lidar", "latent_dim": 12}})");
  CHECK_THAT(testing::ConfigErrorOf([&] { LoadIbCcModel(dir + "/z.json"); }),
             Catch::Contains("/config/latent_dim") && Catch::Contains("4, 8, 16, 32, 64"));

  testing::WriteFile(dir + "/missing.json", R"({"format": "uavsim-ibcc/1", "weights": "no.pt",
    "config": {"modality": "lidar"}})");
  CHECK_THAT(testing::ConfigErrorOf([&] { LoadIbCcModel(dir + "/missing.json"); }),
             Catch::Contains("/weights") && Catch::Contains("file not found"));

  testing::WriteFile(dir + "/format.json", R"({"weights": "lidar.pt", "config": {}})");
  CHECK_THAT(testing::ConfigErrorOf([&] { LoadIbCcModel(dir + "/format.json"); }),
             Catch::Contains("/format") && Catch::Contains("uavsim-ibcc/1"));

  // The weights are a z = 16 LiDAR model; a sidecar claiming z = 8 must not load.
  testing::WriteFile(dir + "/mismatch.json", R"({"format": "uavsim-ibcc/1",
    "weights": "lidar.pt", "config": {"modality": "lidar", "latent_dim": 8}})");
  CHECK_THROWS_WITH(LoadIbCcModel(dir + "/mismatch.json"),
                    Catch::Contains("lidar.pt") && Catch::Contains("do not fit"));
  CHECK(good.find("\"uavsim-ibcc/1\"") != std::string::npos);
}

TEST_CASE("NodeEncoder: loaded model sends mu and decodes world positions", "[pipeline]") {
  InitTorch(1, 33);
  const std::string dir = testing::TempDir("node-encoder");
  for (Modality m : {Modality::kCamera, Modality::kLidar, Modality::kRadar}) {
    const IbCcConfig config = Config(m, 16);
    IbCcModel model(config);
    model->eval();
    const std::string path = dir + "/" + ModalityName(m) + ".json";
    SaveIbCcModel(model, path);

    const auto node = NodeEncoder::Load(path);
    CHECK(node->modality() == m);
    CHECK(node->latent_dim() == 16);
    const IbInput in = InputFor(m, config.normalization);
    torch::NoGradGuard no_grad;
    const torch::Tensor mu = model->Encode(in);
    std::vector<float> latent;
    if (m == Modality::kCamera) {
      latent = node->Encode(SomeCamera(0.7f));  // the second row of InputFor
    } else {
      latent = node->Encode(
          SomeCloud(m, m == Modality::kLidar ? 30 : 9, m == Modality::kLidar ? 3.0f : -2.0f));
    }
    REQUIRE(latent.size() == 16);
    for (int j = 0; j < 16; ++j) CHECK(latent[j] == Approx(mu[1][j].item<float>()).margin(1e-5));
    if (m == Modality::kCamera) CHECK(latent == node->Encode(SomeCamera(0.7f)));  // bit for bit

    const torch::Tensor y = model->Decode(mu.slice(0, 1, 2))[0];
    const Eigen::Vector3d p = node->DecodePosition(latent);
    for (int a = 0; a < 3; ++a)
      CHECK(p[a] ==
            Approx(y[a].item<double>() * 20.0 + config.normalization.centre_m[a]).margin(1e-3));
  }
}

TEST_CASE("NodeEncoder: wrong inputs are refused with a message", "[pipeline]") {
  InitTorch(1, 34);
  const auto lidar = NodeEncoder::Create(Config(Modality::kLidar, 4));
  const auto camera = NodeEncoder::Create(Config(Modality::kCamera, 4));
  CHECK_THROWS_WITH(lidar->Encode(SomeCamera(0.5f)), Catch::Contains("lidar model"));
  CHECK_THROWS_WITH(camera->Encode(SomeCloud(Modality::kLidar, 3, 0.0f)),
                    Catch::Contains("camera model"));
  CHECK_THROWS_WITH(lidar->Encode(SomeCloud(Modality::kRadar, 3, 0.0f)),
                    Catch::Contains("expected 4 channels"));
  CHECK_THROWS_WITH(lidar->Encode(PointObservation{}), Catch::Contains("no points"));
  CHECK_THROWS_WITH(lidar->Encode(SomeCloud(Modality::kLidar, 1025, 0.0f)),
                    Catch::Contains("at most 1024"));
  CameraObservation small = SomeCamera(0.5f);
  small.crop_right.resize(64 * 64);
  CHECK_THROWS_WITH(camera->Encode(small), Catch::Contains("128 x 128"));
  CHECK_THROWS_WITH(camera->DecodePosition({1.0f, 2.0f}), Catch::Contains("expected 4"));
  PointObservation nan_cloud = SomeCloud(Modality::kLidar, 3, 0.0f);
  nan_cloud.values[5] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH(lidar->Encode(nan_cloud), Catch::Contains("point 1 has a non-finite value"));
  CameraObservation inf_crop = SomeCamera(0.5f);
  inf_crop.crop_left[7] = std::numeric_limits<float>::infinity();
  CHECK_THROWS_WITH(camera->Encode(inf_crop), Catch::Contains("non-finite"));
  CHECK(lidar->Encode(SomeCloud(Modality::kLidar, 1, 0.0f)).size() == 4);
}

}  // namespace uavsim::pipeline
