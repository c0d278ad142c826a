// Table III's encoder counts (encoder_flops.h) against closed forms written
// from Table I, and the paper's 147.32 MFLOPs for the image encoder.
#include "pipeline/node/encoder_flops.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>

#include "pipeline/torch_runtime.h"

namespace uavsim::pipeline {
namespace {

// Table I's CNN on one 128 x 128 eye: Conv 3x3 s2 p1 1 -> 32 (64 x 64
// outputs), then 32 -> 64 (32 x 32 outputs).
constexpr std::int64_t kEyeConvMacs = 9 * 1 * 32 * 64 * 64 + 9 * 32 * 64 * 32 * 32;
// IbHead(d, z): mu and sigma MLPs, each Linear(d, 128) -> Linear(128, z).
std::int64_t IbHeadMacs(std::int64_t d, std::int64_t z) { return 2 * (d * 128 + 128 * z); }

IbCcConfig Config(Modality m) {
  IbCcConfig c;
  c.modality = m;
  c.latent_dim = 16;
  return c;
}

TEST_CASE("Encoder FLOPs: the paper's image layout gives Table III's 147.32 MFLOPs", "[pipeline]") {
  InitTorch(1, 1);
  IbCcConfig c = Config(Modality::kCamera);
  c.stereo_branches = StereoBranches::kTwo;
  c.eye_pool_side = 0;
  c.roi_geometry = false;
  const EncoderFlops f = CountEncoderFlops(c);
  CHECK(kEyeConvMacs == 20054016);
  CHECK(f.feature_multiply_adds == 2 * kEyeConvMacs);  // two branches, one eye each
  CHECK(f.feature_dim == 2 * 64 * 32 * 32);
  CHECK(f.bottleneck_multiply_adds == IbHeadMacs(131072, 16));
  CHECK(f.Flops() == 2 * (2 * kEyeConvMacs + IbHeadMacs(131072, 16)));  // 147 333 120
  // The convention: 2 FLOPs per multiply-add of the convolutions and of the
  // mu and sigma first layers is the paper's number to its last digit (the
  // 128 -> z layers add 0.008 M); 1 FLOP per multiply-add is half of it.
  const double paper_terms = 2.0 * (2 * kEyeConvMacs + 2 * 131072 * 128);
  CHECK(std::round(paper_terms / 1e4) / 100.0 == Approx(147.32).margin(1e-9));
  CHECK(f.Flops() / 1e6 == Approx(147.32).margin(0.02));
  // Biases of the convolutions; of the four linear layers, and the two MLPs'
  // ReLU modules.
  CHECK(f.feature_other_ops == 2 * (32 * 64 * 64 + 64 * 32 * 32));
  CHECK(f.bottleneck_other_ops == 2 * (128 + 16) + 2 * 128);
}

TEST_CASE("Encoder FLOPs: our default camera layout", "[pipeline]") {
  InitTorch(1, 1);
  const EncoderFlops f = CountEncoderFlops(Config(Modality::kCamera));
  // The shared CNN on both eyes costs what two branches do; the 4x4 pool and
  // the 18 ROI features shrink the head's input to 2 x 1024 + 18.
  CHECK(f.feature_multiply_adds == 2 * kEyeConvMacs);
  CHECK(f.feature_dim == 2066);
  CHECK(f.bottleneck_multiply_adds == IbHeadMacs(2066, 16));
  // Biases, and the pool: every input element added, every output divided.
  CHECK(f.feature_other_ops == 2 * (32 * 64 * 64 + 64 * 32 * 32) + 2 * (64 * 32 * 32 + 64 * 4 * 4));

  // Two branches with a pool: the pool sees both eyes.
  IbCcConfig two = Config(Modality::kCamera);
  two.stereo_branches = StereoBranches::kTwo;
  CHECK(CountEncoderFlops(two).feature_other_ops == f.feature_other_ops);
}

TEST_CASE("Encoder FLOPs: PointNet on 1024 points is the sum of its layers", "[pipeline]") {
  InitTorch(1, 1);
  for (const auto& [m, channels] :
       {std::pair{Modality::kLidar, 4}, std::pair{Modality::kRadar, 5}}) {
    INFO(channels << " channels");
    const EncoderFlops f = CountEncoderFlops(Config(m), 1024);
    // H_l = ReLU(BN(Conv1d_{P_{l-1} -> P_l})), P = C, 64, 64, 64, 128, 1024,
    // the same weights at every point; no conv bias.
    const std::int64_t widths[] = {channels, 64, 64, 64, 128, 1024};
    std::int64_t macs = 0, batch_norm = 0;
    for (int l = 1; l <= 5; ++l) {
      macs += 1024 * widths[l - 1] * widths[l];
      batch_norm += 2 * 1024 * widths[l];
    }
    CHECK(f.feature_multiply_adds == macs);
    CHECK(f.feature_multiply_adds == 1024 * (64 * channels + 147456));
    CHECK(f.feature_other_ops == batch_norm);
    CHECK(f.feature_dim == 1024);
    CHECK(f.bottleneck_multiply_adds == IbHeadMacs(1024, 16));
    CHECK(f.input == "1024 points x " + std::to_string(channels) + " channels");
  }
  CHECK(CountEncoderFlops(Config(Modality::kLidar), 1).feature_multiply_adds == 64 * 4 + 147456);
  CHECK_THROWS_WITH(CountEncoderFlops(Config(Modality::kLidar), 0),
                    "CountEncoderFlops: points must be >= 1, got 0");
}

TEST_CASE("Encoder FLOPs: the MLP baseline's head", "[pipeline]") {
  InitTorch(1, 1);
  IbCcConfig c = Config(Modality::kLidar);
  c.bottleneck = IbBottleneck::kMlp;
  const std::int64_t hidden = 256;  // MlpCompressor::MatchedHidden(1024, 16)
  CHECK(CountEncoderFlops(c).bottleneck_multiply_adds == 1024 * hidden + hidden * 16);
}

}  // namespace
}  // namespace uavsim::pipeline
