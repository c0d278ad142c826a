#include "pipeline/node/node_encoder.h"

#include <stdexcept>
#include <string>

#include "pipeline/node/ib_encoder.h"
#include "pipeline/node/ib_model_io.h"

namespace uavsim::pipeline {

struct NodeEncoder::Impl {
  IbCcModel model{nullptr};
};

namespace {

std::vector<float> ToVector(const torch::Tensor& row) {
  const torch::Tensor c = row.contiguous();
  const float* p = c.data_ptr<float>();
  return std::vector<float>(p, p + c.numel());
}

}  // namespace

NodeEncoder::NodeEncoder(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NodeEncoder::~NodeEncoder() = default;

std::unique_ptr<NodeEncoder> NodeEncoder::Load(const std::string& model_json) {
  auto impl = std::make_unique<Impl>();
  impl->model = LoadIbCcModel(model_json);
  return std::unique_ptr<NodeEncoder>(new NodeEncoder(std::move(impl)));
}

std::unique_ptr<NodeEncoder> NodeEncoder::Create(const IbCcConfig& config) {
  auto impl = std::make_unique<Impl>();
  impl->model = IbCcModel(config);
  impl->model->eval();
  return std::unique_ptr<NodeEncoder>(new NodeEncoder(std::move(impl)));
}

const IbCcConfig& NodeEncoder::config() const { return impl_->model->config(); }

std::vector<float> NodeEncoder::Encode(const CameraObservation& obs) const {
  if (modality() != Modality::kCamera)
    throw std::invalid_argument(std::string("NodeEncoder: a camera frame given to the ") +
                                ModalityName(modality()) + " model");
  torch::NoGradGuard no_grad;
  const IbInput in = MakeCameraInput({&obs}, config().normalization);
  return ToVector(impl_->model->Encode(in)[0]);
}

std::vector<float> NodeEncoder::Encode(const PointObservation& obs) const {
  if (modality() == Modality::kCamera)
    throw std::invalid_argument("NodeEncoder: a point cloud given to the camera model");
  torch::NoGradGuard no_grad;
  // One cloud: no padding, so the encoder runs on exactly obs.count() points.
  const IbInput in = MakePointInput({&obs}, modality(), config().normalization);
  return ToVector(impl_->model->Encode(in)[0]);
}

Eigen::Vector3d NodeEncoder::DecodePosition(const std::vector<float>& latent) const {
  if (static_cast<int>(latent.size()) != latent_dim())
    throw std::invalid_argument("NodeEncoder::DecodePosition: expected " +
                                std::to_string(latent_dim()) + " latent values, got " +
                                std::to_string(latent.size()));
  torch::NoGradGuard no_grad;
  torch::Tensor t = torch::from_blob(const_cast<float*>(latent.data()),
                                     {1, static_cast<std::int64_t>(latent.size())})
                        .clone();
  const torch::Tensor y = impl_->model->Decode(t)[0];
  const Eigen::Vector3d p_n(y[0].item<float>(), y[1].item<float>(), y[2].item<float>());
  return DenormalizePosition(p_n, config().normalization);
}

}  // namespace uavsim::pipeline
