#include "pipeline/node/encoder_flops.h"

#include <stdexcept>
#include <vector>

#include "pipeline/flops.h"
#include "pipeline/node/ib_encoder.h"

namespace uavsim::pipeline {
namespace {

const torch::nn::Module& Child(const IbCcModelImpl& model, const char* name) {
  const auto* child = model.named_children().find(name);
  if (!child) throw std::logic_error(std::string("CountEncoderFlops: no module ") + name);
  return **child;
}

}  // namespace

EncoderFlops CountEncoderFlops(const IbCcConfig& config, int points) {
  if (points < 1)
    throw std::invalid_argument("CountEncoderFlops: points must be >= 1, got " +
                                std::to_string(points));
  const IbCcModel model(config);
  EncoderFlops out;
  out.feature_dim = model->feature_dim();

  FlopCount encoder;
  if (config.modality == Modality::kCamera) {
    constexpr std::int64_t kSide = CameraObservation::kCropPx;
    const torch::nn::Module& cnn = Child(*model, "image_encoder");
    if (config.stereo_branches == StereoBranches::kShared) {
      // forward() runs the shared CNN (and the pool) once on both eyes as a batch of two.
      out.input = "2 eyes x 1 x 128 x 128, one shared CNN";
      encoder = CountFlops(cnn, {2, 1, kSide, kSide});
    } else {
      // Each eye through its own branch; the pool, if any, then sees both eyes.
      out.input = "2 eyes x 1 x 128 x 128, two CNN branches";
      const std::vector<std::int64_t> eye{1, 1, kSide, kSide};
      encoder = CountFlops(cnn, eye, {{"conv1_right", eye}});
      if (config.eye_pool_side > 0) {
        std::vector<std::int64_t> maps;
        for (const LayerFlops& l : encoder.layers)
          if (l.name == "conv2_right") maps = l.output_shape;
        maps.at(0) = 2;
        encoder = CountFlops(cnn, eye, {{"conv1_right", eye}, {"pool", maps}});
      }
    }
  } else {
    const std::int64_t channels = PointChannels(config.modality);
    out.input = std::to_string(points) + " points x " + std::to_string(channels) + " channels";
    encoder = CountFlops(Child(*model, "point_encoder"), {1, channels, points});
  }
  out.feature_multiply_adds = encoder.MultiplyAdds();
  out.feature_other_ops = encoder.OtherOps();

  const std::vector<std::int64_t> h{1, out.feature_dim};
  const FlopCount head = config.bottleneck == IbBottleneck::kIb
                             ? CountFlops(Child(*model, "ib_head"), h, {{"sigma_mlp.0", h}})
                             : CountFlops(Child(*model, "mlp_compressor"), h);
  out.bottleneck_multiply_adds = head.MultiplyAdds();
  out.bottleneck_other_ops = head.OtherOps();
  return out;
}

}  // namespace uavsim::pipeline
