// Table III of the paper, encoder columns: the FLOPs a sensing node spends
// per frame in its network (feature encoder and bottleneck; the decoder
// runs only in training), counted by CountFlops (pipeline/flops.h) from the
// layers of the very IbCcModel that an IbCcConfig builds. LibTorch-free
// interface; call pipeline::InitTorch() first (the model is built, with
// untrained weights, to be walked; it is never run).
//
// Convention: 2 FLOPs per multiply-add of a weight, the convention that
// reproduces the paper's 147.32 MFLOPs (pipeline/flops.h). Bias adds,
// BatchNorm, pooling and the ReLU modules are counted apart (other_ops);
// functional operations inside forward() (ReLU of the CNNs and of
// PointNet, concatenation, the global max, softplus) are not counted.
#pragma once

#include <cstdint>
#include <string>

#include "pipeline/node/ib_cc_config.h"

namespace uavsim::pipeline {

struct EncoderFlops {
  std::string input;             // what one frame feeds the encoder, e.g. "2 x 1 x 128 x 128"
  std::int64_t feature_dim = 0;  // d, the bottleneck's input
  std::int64_t feature_multiply_adds = 0, feature_other_ops = 0;
  std::int64_t bottleneck_multiply_adds = 0, bottleneck_other_ops = 0;

  std::int64_t FeatureFlops() const { return 2 * feature_multiply_adds; }
  std::int64_t BottleneckFlops() const { return 2 * bottleneck_multiply_adds; }
  std::int64_t Flops() const { return FeatureFlops() + BottleneckFlops(); }
};

// One frame of `config.modality`: the camera's two 128 x 128 crops (the
// shared CNN runs on both eyes as a batch of two; with two branches each
// branch on its own eye), or `points` points of PointChannels(modality)
// channels. Throws std::invalid_argument for points < 1 or a config that
// IbCcModel refuses.
EncoderFlops CountEncoderFlops(const IbCcConfig& config, int points = 1024);

}  // namespace uavsim::pipeline
