// FLOPs of a LibTorch module counted from its layers' shapes (issue 20 item
// 7, the paper's Table III). LibTorch's C++ API has no forward hooks, so
// the count does not run the module: it walks module.named_modules() in
// registration order and, for each leaf layer, derives the output shape
// from the layer's own options (channels, kernel size, stride, padding,
// dilation, groups, in/out features) and the shape that reaches it.
//
// Convention (the paper's, checked in tests/pipeline/flops_test.cpp): one
// multiply-add of a weight (Conv1d, Conv2d, Linear) is 2 FLOPs; the paper's
// 147.32 MFLOPs for the image encoder is exactly 2 x the multiply-adds of
// its convolutions and of the mu and sigma MLPs' first layers (1 FLOP per
// multiply-add would give 73.66). Everything else a layer does (bias adds,
// BatchNorm's scale and shift, ReLU, pooling) is counted apart, one
// operation per element, and left out of flops(). Counts are for inference
// (eval mode: Dropout costs nothing, BatchNorm is an affine map).
// Operations a module's forward() applies as functions rather than as
// registered modules (torch::relu, torch::cat, amax, softplus) are not
// seen and not counted.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace uavsim::pipeline {

// One leaf layer for one input.
struct LayerFlops {
  std::string name;  // as named_modules() names it: "conv1", "mu_mlp.0"
  std::string type;  // "Conv2d", "Linear", "BatchNorm1d", ...
  std::vector<std::int64_t> input_shape, output_shape;
  std::int64_t multiply_adds = 0;  // of the weights (Conv1d, Conv2d, Linear)
  std::int64_t other_ops = 0;      // bias adds, BatchNorm, ReLU, pooling: one per element
};

struct FlopCount {
  std::vector<LayerFlops> layers;  // leaf layers in registration order

  std::int64_t MultiplyAdds() const;
  std::int64_t OtherOps() const;
  // The paper's convention: 2 FLOPs per multiply-add.
  std::int64_t Flops() const { return 2 * MultiplyAdds(); }
};

// Walks `module`'s leaf layers in registration order. The first takes
// `input_shape` (batch first: [B, C, L] for Conv1d, [B, C, H, W] for
// Conv2d, [..., F] for Linear); every other takes the output shape of the
// leaf before it, unless `branch_inputs` names it (by its named_modules()
// name): then it takes the shape given there. That is how parallel
// branches are described: e.g. {"conv1_right": [1, 1, 128, 128]} for the
// right eye's CNN, {"sigma_mlp.0": [1, d]} for the sigma MLP, each fed the
// input its forward() gives it.
//
// Known leaves: Conv1d, Conv2d, Linear, BatchNorm1d, BatchNorm2d, ReLU,
// Dropout, AdaptiveAvgPool2d. Throws std::invalid_argument naming the layer
// for any other leaf type, for a shape whose channel or feature count
// differs from the layer's (so a wrongly described graph fails instead of
// giving a number), for an output size below 1, and for a branch_inputs
// name that is no leaf layer of `module`.
FlopCount CountFlops(const torch::nn::Module& module, const std::vector<std::int64_t>& input_shape,
                     const std::map<std::string, std::vector<std::int64_t>>& branch_inputs = {});

}  // namespace uavsim::pipeline
