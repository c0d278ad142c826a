// The sensing node's IB-CC encoder as the engine calls it at run time:
// observation in, latent mu out (paper Sec. IV-B: the node sends mu). Torch-
// free header (PIMPL), so the engine never includes <torch/torch.h>.
//
// Call pipeline::InitTorch() once before Load/Create. Encoding runs in eval
// mode without autograd and is deterministic: the same model and observation
// give the same latent bit for bit at a fixed thread count. One instance per
// node; calls on one instance must not overlap.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "pipeline/node/ib_cc_config.h"
#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

class NodeEncoder {
 public:
  // A trained model from its JSON sidecar (see ib_model_io.h). Throws
  // core::ConfigError for a bad or missing sidecar or weights file,
  // std::runtime_error for weights that do not fit the configuration.
  static std::unique_ptr<NodeEncoder> Load(const std::string& model_json);
  // Fresh untrained weights drawn from LibTorch's generator (for tests and
  // benchmarks). Throws std::invalid_argument for an invalid config.
  static std::unique_ptr<NodeEncoder> Create(const IbCcConfig& config);

  ~NodeEncoder();
  NodeEncoder(const NodeEncoder&) = delete;
  NodeEncoder& operator=(const NodeEncoder&) = delete;

  const IbCcConfig& config() const;
  Modality modality() const { return config().modality; }
  int latent_dim() const { return config().latent_dim; }

  // mu in R^z for one camera frame. The crops are encoded whatever
  // obs.detected says: a node that detected nothing should send nothing.
  // Throws std::invalid_argument if the model is not a camera model or a crop
  // is not 128 x 128 finite values.
  std::vector<float> Encode(const CameraObservation& obs) const;
  // mu in R^z for one point cloud (1..1024 points). Throws
  // std::invalid_argument if the modality or channel count does not match
  // the model, the cloud is empty or has more than 1024 points, or a value
  // is not finite.
  std::vector<float> Encode(const PointObservation& obs) const;

  // The training decoder's single-modality position estimate for a latent
  // (world ENU, metres): the paper's per-modality RMSE curves (Figs. 7-9).
  // Throws std::invalid_argument if latent.size() != latent_dim().
  Eigen::Vector3d DecodePosition(const std::vector<float>& latent) const;

 private:
  struct Impl;
  explicit NodeEncoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::pipeline
