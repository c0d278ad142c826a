// CountFlops (pipeline/flops.h) against hand counts: one convolution and one
// linear layer written out from their definitions, the shapes it derives,
// branches, and the errors of a wrongly described graph.
#include "pipeline/flops.h"

#include <torch/torch.h>

#include <catch2/catch.hpp>
#include <stdexcept>

#include "pipeline/torch_runtime.h"

namespace uavsim::pipeline {
namespace {

using Shape = std::vector<std::int64_t>;

TEST_CASE("CountFlops: a 3x3 stride-2 convolution matches the hand count", "[pipeline]") {
  InitTorch(1, 1);
  // Table I's first layer: Conv 3x3, s = 2, p = 1, 1 -> 32, on 128 x 128.
  // Output side floor((128 + 2 - 2 - 1) / 2) + 1 = 64; each of the
  // 32 x 64 x 64 outputs takes 3 x 3 x 1 multiply-adds.
  torch::nn::Sequential net(
      torch::nn::Conv2d(torch::nn::Conv2dOptions(1, 32, 3).stride(2).padding(1)));
  const FlopCount c = CountFlops(*net, {1, 1, 128, 128});
  REQUIRE(c.layers.size() == 1);
  const LayerFlops& l = c.layers[0];
  CHECK(l.name == "0");
  CHECK(l.type == "Conv2d");
  CHECK(l.output_shape == Shape{1, 32, 64, 64});
  CHECK(l.multiply_adds == 3 * 3 * 1 * 32 * 64 * 64);  // 1 179 648
  CHECK(c.Flops() == 2 * 1179648);
  CHECK(l.other_ops == 32 * 64 * 64);  // one bias add per output
  // The shape agrees with what the layer computes.
  CHECK(net->forward(torch::zeros({1, 1, 128, 128})).sizes() == torch::IntArrayRef(l.output_shape));

  // Without padding, dilation 2, groups 2, a batch of 3, an odd side:
  // side floor((31 - 2 * 2 - 1) / 1) + 1 = 27; 4 / 2 input channels a group.
  torch::nn::Sequential grouped(
      torch::nn::Conv2d(torch::nn::Conv2dOptions(4, 6, 3).dilation(2).groups(2).bias(false)));
  const LayerFlops g = CountFlops(*grouped, {3, 4, 31, 31}).layers.at(0);
  CHECK(g.output_shape == Shape{3, 6, 27, 27});
  CHECK(g.multiply_adds == 3 * 6 * 27 * 27 * (2 * 3 * 3));
  CHECK(g.other_ops == 0);
  CHECK(grouped->forward(torch::zeros({3, 4, 31, 31})).sizes() ==
        torch::IntArrayRef(g.output_shape));
}

TEST_CASE("CountFlops: a linear layer matches the hand count", "[pipeline]") {
  InitTorch(1, 1);
  // The mu MLP's first layer at the paper's layout: 2 x 64 x 32 x 32 =
  // 131 072 inputs, 128 outputs: 131072 x 128 multiply-adds, 128 bias adds.
  torch::nn::Sequential net(torch::nn::Linear(131072, 128), torch::nn::ReLU(),
                            torch::nn::Linear(128, 16));
  const FlopCount c = CountFlops(*net, {1, 131072});
  REQUIRE(c.layers.size() == 3);
  CHECK(c.layers[0].multiply_adds == 16777216);
  CHECK(c.layers[0].other_ops == 128);
  CHECK(c.layers[1].type == "ReLU");
  CHECK(c.layers[1].other_ops == 128);
  CHECK(c.layers[2].multiply_adds == 128 * 16);
  CHECK(c.layers[2].output_shape == Shape{1, 16});
  CHECK(c.MultiplyAdds() == 16777216 + 2048);
  CHECK(c.OtherOps() == 128 + 128 + 16);
  // Leading dimensions multiply: 5 x 7 rows.
  torch::nn::Sequential small(torch::nn::Linear(3, 2));
  CHECK(CountFlops(*small, {5, 7, 3}).MultiplyAdds() == 5 * 7 * 3 * 2);
}

TEST_CASE("CountFlops: Conv1d, BatchNorm, pooling and branches", "[pipeline]") {
  InitTorch(1, 1);
  torch::nn::Sequential points(torch::nn::Conv1d(torch::nn::Conv1dOptions(4, 64, 1).bias(false)),
                               torch::nn::BatchNorm1d(64), torch::nn::Dropout(0.1));
  const FlopCount p = CountFlops(*points, {1, 4, 1024});
  CHECK(p.layers[0].multiply_adds == 1024 * 4 * 64);
  CHECK(p.layers[1].other_ops == 2 * 64 * 1024);  // scale and shift
  CHECK(p.layers[2].other_ops == 0);              // Dropout: the identity in eval mode
  CHECK(p.layers[2].output_shape == Shape{1, 64, 1024});

  torch::nn::Sequential pool(torch::nn::AdaptiveAvgPool2d(torch::nn::AdaptiveAvgPool2dOptions(4)));
  const LayerFlops q = CountFlops(*pool, {2, 64, 32, 32}).layers.at(0);
  CHECK(q.output_shape == Shape{2, 64, 4, 4});
  CHECK(q.other_ops == 2 * 64 * 32 * 32 + 2 * 64 * 4 * 4);

  // Two parallel heads on the same input: without the branch input the
  // second head would be handed the first one's output and is refused.
  torch::nn::Sequential two(torch::nn::Linear(10, 3), torch::nn::Linear(10, 5));
  CHECK(CountFlops(*two, {1, 10}, {{"1", {1, 10}}}).MultiplyAdds() == 10 * 3 + 10 * 5);
  CHECK_THROWS_WITH(CountFlops(*two, {1, 10}),
                    "CountFlops: 1 (Linear): expected 10 input features, got shape [1, 3]");
}

TEST_CASE("CountFlops: errors name the layer", "[pipeline]") {
  InitTorch(1, 1);
  torch::nn::Sequential conv(torch::nn::Conv2d(torch::nn::Conv2dOptions(3, 8, 3)));
  CHECK_THROWS_WITH(CountFlops(*conv, {1, 1, 16, 16}),
                    "CountFlops: 0 (Conv2d): expected 3 input channels, got shape [1, 1, 16, 16]");
  CHECK_THROWS_WITH(CountFlops(*conv, {1, 3, 16}),
                    "CountFlops: 0 (Conv2d): expected an input of 4 dimensions, got [1, 3, 16]");
  CHECK_THROWS_WITH(CountFlops(*conv, {1, 3, 2, 2}),
                    "CountFlops: 0 (Conv2d): the input [1, 3, 2, 2] leaves no output");
  CHECK_THROWS_WITH(CountFlops(*conv, {1, 3, 16, 16}, {{"conv9", {1, 3, 16, 16}}}),
                    "CountFlops: branch input 'conv9' names no leaf layer of the module");
  torch::nn::Sequential gelu{torch::nn::GELU()};
  CHECK_THROWS_WITH(CountFlops(*gelu, {1, 4}), Catch::Contains("no FLOP rule for this layer type"));
}

}  // namespace
}  // namespace uavsim::pipeline
