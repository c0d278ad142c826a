// IB-CC: information-bottleneck collaborative compression at a sensing node
// (paper Sec. IV-B, Table I), in LibTorch. Per modality:
//
//   feature encoder  camera: ImageFeatureEncoder (both stereo eyes, dropout,
//                    optionally ROI geometry); LiDAR/radar: PointNetEncoder
//   bottleneck       IbHead (mu, sigma MLPs; t = mu + sigma * eps) or the
//                    MlpCompressor baseline (deterministic, no KL)
//   decoder          IbDecoder -> 3-D position (training only)
//   loss             L = ||y - y_hat||^2 + beta * D_KL
//
// Shapes are [batch, ...] float32 on the CPU. Positions are normalised (see
// ib_normalization.h). Call pipeline::InitTorch() before any use. Randomness
// (initial weights, dropout, eps) comes from LibTorch's global generator: the
// same torch::manual_seed and thread count give the same numbers. Shape and
// content errors throw std::invalid_argument naming what was expected.
#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <vector>

#include "pipeline/node/ib_cc_config.h"
#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

// A batch of network inputs for one modality. Camera: left, right
// [B, 1, 128, 128] grey in [0, 1]; geometry [B, kCameraGeometryFeatures].
// LiDAR/radar: points [B, C, N] (normalised, channel-major), mask [B, N]
// bool, true for real points; padded slots may hold anything.
struct IbInput {
  torch::Tensor left, right, geometry;
  torch::Tensor points, mask;
  std::int64_t batch_size() const;
};

// Builds a camera batch (whatever `detected` says). Throws
// std::invalid_argument if the list is empty or a crop is not kCropPx *
// kCropPx finite values.
IbInput MakeCameraInput(const std::vector<const CameraObservation*>& obs, const IbNormalization& n);
// Builds a point batch padded to the largest cloud in it (N = max count).
// Throws std::invalid_argument for an empty list, an empty cloud, or what
// NormalizePoints rejects.
IbInput MakePointInput(const std::vector<const PointObservation*>& obs, Modality m,
                       const IbNormalization& n);
// Normalised target positions [B, 3] from world positions.
torch::Tensor MakePositionTarget(const std::vector<Eigen::Vector3d>& positions_w,
                                 const IbNormalization& n);

// Table I, image feature encoder, per stereo eye:
//   ReLU(Conv 3x3 s2 p1, 1 -> 32) -> ReLU(Conv 3x3 s2 p1, 32 -> 64)
//   128x128 -> 32x64x64 -> 64x32x32 -> [average pool to 64xSxS] -> flatten:
//   h^left, h^right in R^(64 S^2) each (S = eye_pool_side; 32 without a pool).
// h^c = Dropout(Concat(h^left, h^right)) (paper eq. for h^c), then, with
// roi_geometry, the ROI geometry is appended: output [B, features()].
// The eyes run through two parallel branches (StereoBranches::kTwo, the
// paper; modules conv1, conv2 for the left eye and conv1_right, conv2_right)
// or one CNN with shared weights (kShared, ours: one pass over both eyes).
// The switches are IbCcConfig's; the defaults are the layout older models
// were saved with.
class ImageFeatureEncoderImpl : public torch::nn::Module {
 public:
  ImageFeatureEncoderImpl(double dropout = 0.1, StereoBranches branches = StereoBranches::kShared,
                          int eye_pool_side = 4, bool roi_geometry = true);

  // Features of one eye and of the whole output (2 eyes + the geometry).
  std::int64_t eye_features() const;
  std::int64_t features() const;

  // Both conv stages of one branch (`right`: the right eye's; the same as the
  // left's with shared weights) for eyes [B, 1, 128, 128]:
  // {[B, 32, 64, 64], [B, 64, 32, 32]}.
  std::vector<torch::Tensor> FeatureMaps(const torch::Tensor& eyes, bool right = false);
  // geometry [B, 18] is required in every layout (ignored without roi_geometry).
  torch::Tensor forward(const torch::Tensor& left, const torch::Tensor& right,
                        const torch::Tensor& geometry);

 private:
  StereoBranches branches_;
  int eye_pool_side_;
  bool roi_geometry_;
  torch::nn::Conv2d conv1_{nullptr}, conv2_{nullptr};
  torch::nn::Conv2d conv1_right_{nullptr}, conv2_right_{nullptr};  // kTwo only
  torch::nn::AdaptiveAvgPool2d pool_{nullptr};                     // eye_pool_side > 0 only
  torch::nn::Dropout dropout_{nullptr};
};
TORCH_MODULE(ImageFeatureEncoder);

// Table I, point cloud feature encoder (PointNet without its T-nets):
//   H_l = ReLU(BN(Conv1d_{P_{l-1} -> P_l}(H_{l-1}))), P = C, 64, 64, 64, 128, 1024
//   MaxPool_global(H_5) in R^1024.
// Only the real points are computed: they are packed into one sequence, so
// padding affects neither the BatchNorm statistics nor the max. Input points
// [B, C, N], mask [B, N]; output [B, features()]. Every cloud needs at least
// one real point, and in training with BatchNorm the batch needs at least two.
//
// Switches (IbCcConfig; the defaults are the paper's): with
// PointFrame::kCentroid each cloud's x, y, z (channels 0-2) are taken
// relative to its centroid c (mean over its real points) and c is appended
// to the pooled feature: [B, 1027], max-pooled features that do not move
// when the cloud does, and the position in three numbers. PointNorm::kGroup
// replaces each BatchNorm by a GroupNorm (8 groups) of each point's
// channels, PointNorm::kNone drops it (the convolutions then get a bias):
// either way a cloud's features do not depend on the rest of its batch.
//
// In eval mode under torch::NoGradGuard each BatchNorm (or bias) is folded
// into the convolution before it (the same affine map, one matrix product
// per layer). The folded weights are cached until the next train()/eval()
// call or load(); after changing weights in place while in eval mode, call
// eval() again. GroupNorm is not folded.
class PointNetEncoderImpl : public torch::nn::Module {
 public:
  static constexpr std::int64_t kFeatures = 1024;

  explicit PointNetEncoderImpl(std::int64_t in_channels, PointFrame frame = PointFrame::kScene,
                               PointNorm norm = PointNorm::kBatch);

  // Per-point features H_5 [P, 1024] of real points x [P, C] (one row each).
  torch::Tensor PointFeatures(const torch::Tensor& x);
  torch::Tensor forward(const torch::Tensor& points, const torch::Tensor& mask);

  std::int64_t in_channels() const { return in_channels_; }
  std::int64_t features() const;

  void train(bool on = true) override;
  void load(torch::serialize::InputArchive& archive) override;

 private:
  torch::Tensor FoldedPointFeatures(torch::Tensor x);
  torch::Tensor Pooled(const torch::Tensor& points, const torch::Tensor& mask);

  std::int64_t in_channels_;
  PointFrame frame_;
  PointNorm norm_;
  std::vector<torch::nn::Conv1d> convs_;
  std::vector<torch::nn::BatchNorm1d> norms_;               // kBatch
  std::vector<torch::nn::GroupNorm> group_norms_;           // kGroup
  std::vector<torch::Tensor> folded_weight_, folded_bias_;  // eval-mode cache
};
TORCH_MODULE(PointNetEncoder);

// What a bottleneck produces for h [B, d]: all [B, z]. `t` is the latent the
// decoder sees: a sample in training, mu in eval (the node sends mu). The
// MLP baseline leaves sigma undefined and sets t = mu = its code.
struct IbHeadOutput {
  torch::Tensor mu, sigma, t;
};

// The paper's compression encoder: mu = MLP_mu(h), sigma = MLP_sigma(h), each
// Linear(d, 128) -> ReLU -> Linear(128, z). sigma = softplus(s - 5) + 1e-6,
// as in Alemi et al.'s VIB (the paper's [alemi2016deep]): positive, starting
// small, log sigma^2 always finite. Training: t = mu + sigma * eps,
// eps ~ N(0, I) (reparameterisation); eval: t = mu.
class IbHeadImpl : public torch::nn::Module {
 public:
  static constexpr std::int64_t kHidden = 128;

  IbHeadImpl(std::int64_t in_features, std::int64_t latent_dim);
  IbHeadOutput forward(const torch::Tensor& h);

 private:
  torch::nn::Sequential mu_mlp_{nullptr}, sigma_mlp_{nullptr};
};
TORCH_MODULE(IbHead);

// The paper's MLP baseline replacing IbHead: Linear(d, H) -> ReLU ->
// Linear(H, z), the same depth (two layers) with H = MatchedHidden(d, z) so
// its parameter count equals IbHead's to within z parameters (H = 256 for
// every d and z <= 64). Deterministic in training and eval.
class MlpCompressorImpl : public torch::nn::Module {
 public:
  // Hidden width whose parameter count is closest to IbHead(d, z)'s.
  static std::int64_t MatchedHidden(std::int64_t in_features, std::int64_t latent_dim);

  MlpCompressorImpl(std::int64_t in_features, std::int64_t latent_dim);
  IbHeadOutput forward(const torch::Tensor& h);

 private:
  torch::nn::Sequential mlp_{nullptr};
};
TORCH_MODULE(MlpCompressor);

// Table I, IB decoder MLP_64(Dropout(ReLU(MLP_128(t)))), read as
// Linear(z, 128) -> ReLU -> Dropout -> Linear(128, 64) -> ReLU -> Linear(64, 3).
// t [B, z] -> y_hat [B, 3] (normalised position).
class IbDecoderImpl : public torch::nn::Module {
 public:
  IbDecoderImpl(std::int64_t latent_dim, double dropout = 0.1);
  torch::Tensor forward(const torch::Tensor& t);

 private:
  torch::nn::Sequential mlp_{nullptr};
};
TORCH_MODULE(IbDecoder);

// Paper eq. for D_KL(q(t|h) || N(0, I)) = 1/2 sum_j (mu_j^2 + sigma_j^2 -
// log sigma_j^2 - 1), summed over the last dimension: mu, sigma [B, z] -> [B].
// sigma must be positive.
torch::Tensor KlDivergence(const torch::Tensor& mu, const torch::Tensor& sigma);

// Everything one modality's IB-CC model computes for a batch.
struct IbOutput {
  torch::Tensor features;  // h [B, d]: encoder output
  torch::Tensor mu, sigma, t;
  torch::Tensor y_hat;  // [B, 3]
};

// L = L_MSE + beta * D_KL (paper eq. for L_ALL), each a batch mean; L_MSE =
// ||y - y_hat||^2 summed over x, y, z, in m^2 or normalised units
// (IbCcConfig::mse_units). kl is 0 for the MLP baseline.
struct IbLoss {
  torch::Tensor total, mse, kl;
};

// One modality's model: feature encoder + bottleneck + decoder.
class IbCcModelImpl : public torch::nn::Module {
 public:
  // Throws std::invalid_argument for a latent_dim < 1 or dropout outside [0, 1).
  explicit IbCcModelImpl(const IbCcConfig& config);

  IbOutput forward(const IbInput& in);
  // The latent the node sends: mu [B, z] (the code for the MLP baseline).
  // Honours train()/eval() like forward; wrap in torch::NoGradGuard at run time.
  torch::Tensor Encode(const IbInput& in);
  torch::Tensor Decode(const torch::Tensor& t);
  IbLoss Loss(const IbOutput& out, const torch::Tensor& y) const;

  const IbCcConfig& config() const { return config_; }
  std::int64_t feature_dim() const { return feature_dim_; }
  // Parameters of the bottleneck alone (IbHead or MlpCompressor).
  std::int64_t BottleneckParameterCount() const;

 private:
  torch::Tensor Features(const IbInput& in);
  IbHeadOutput Bottleneck(const torch::Tensor& h);

  IbCcConfig config_;
  std::int64_t feature_dim_ = 0;
  ImageFeatureEncoder image_encoder_{nullptr};
  PointNetEncoder point_encoder_{nullptr};
  IbHead ib_head_{nullptr};
  MlpCompressor mlp_compressor_{nullptr};
  IbDecoder decoder_{nullptr};
};
TORCH_MODULE(IbCcModel);

// Number of scalar parameters of a module and its children.
std::int64_t ParameterCount(const torch::nn::Module& m);

}  // namespace uavsim::pipeline
