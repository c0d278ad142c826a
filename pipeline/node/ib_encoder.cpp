#include "pipeline/node/ib_encoder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace uavsim::pipeline {
namespace {

namespace F = torch::nn::functional;

std::string ShapeOf(const torch::Tensor& x) {
  if (!x.defined()) return "an undefined tensor";
  std::ostringstream s;
  s << "shape " << x.sizes();
  return s.str();
}

[[noreturn]] void Fail(const std::string& what, const std::string& expected,
                       const torch::Tensor& got) {
  throw std::invalid_argument(what + ": expected " + expected + ", got " + ShapeOf(got));
}

bool HasShape(const torch::Tensor& x, std::initializer_list<std::int64_t> shape) {
  if (!x.defined() || x.dim() != static_cast<std::int64_t>(shape.size())) return false;
  std::int64_t d = 0;
  for (std::int64_t s : shape) {
    if (s >= 0 && x.size(d) != s) return false;
    ++d;
  }
  return true;
}

torch::nn::Sequential TwoLayerMlp(std::int64_t in, std::int64_t hidden, std::int64_t out) {
  return torch::nn::Sequential(torch::nn::Linear(in, hidden), torch::nn::ReLU(),
                               torch::nn::Linear(hidden, out));
}

// Parameters of Linear(d, h) -> Linear(h, z), biases included.
std::int64_t TwoLayerParameters(std::int64_t d, std::int64_t h, std::int64_t z) {
  return d * h + h + h * z + z;
}

}  // namespace

std::int64_t IbInput::batch_size() const {
  if (left.defined()) return left.size(0);
  if (points.defined()) return points.size(0);
  return 0;
}

IbInput MakeCameraInput(const std::vector<const CameraObservation*>& obs,
                        const IbNormalization& n) {
  if (obs.empty()) throw std::invalid_argument("MakeCameraInput: no observations");
  constexpr std::int64_t kSide = CameraObservation::kCropPx;
  constexpr std::size_t kPixels = static_cast<std::size_t>(kSide * kSide);
  const auto b = static_cast<std::int64_t>(obs.size());
  IbInput in;
  in.left = torch::empty({b, 1, kSide, kSide});
  in.right = torch::empty({b, 1, kSide, kSide});
  in.geometry = torch::empty({b, kCameraGeometryFeatures});
  float* left = in.left.data_ptr<float>();
  float* right = in.right.data_ptr<float>();
  float* geometry = in.geometry.data_ptr<float>();
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const CameraObservation& o = *obs[i];
    if (o.crop_left.size() != kPixels || o.crop_right.size() != kPixels)
      throw std::invalid_argument("MakeCameraInput: observation " + std::to_string(i) +
                                  ": expected crops of " + std::to_string(kPixels) +
                                  " values (128 x 128), got " + std::to_string(o.crop_left.size()) +
                                  " and " + std::to_string(o.crop_right.size()));
    const auto finite = [](float v) { return std::isfinite(v); };
    if (!std::all_of(o.crop_left.begin(), o.crop_left.end(), finite) ||
        !std::all_of(o.crop_right.begin(), o.crop_right.end(), finite))
      throw std::invalid_argument("MakeCameraInput: observation " + std::to_string(i) +
                                  ": a crop holds a non-finite value");
    std::memcpy(left + i * kPixels, o.crop_left.data(), kPixels * sizeof(float));
    std::memcpy(right + i * kPixels, o.crop_right.data(), kPixels * sizeof(float));
    const std::vector<float> g = CameraGeometryFeatures(o, n);
    std::copy(g.begin(), g.end(), geometry + i * kCameraGeometryFeatures);
  }
  return in;
}

IbInput MakePointInput(const std::vector<const PointObservation*>& obs, Modality m,
                       const IbNormalization& n) {
  if (obs.empty()) throw std::invalid_argument("MakePointInput: no observations");
  const std::int64_t channels = PointChannels(m);
  std::size_t max_count = 0;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (obs[i]->count() == 0)
      throw std::invalid_argument("MakePointInput: observation " + std::to_string(i) +
                                  " has no points (an empty frame is a missing modality, "
                                  "not an encoder input)");
    max_count = std::max(max_count, obs[i]->count());
  }
  const auto b = static_cast<std::int64_t>(obs.size());
  const auto big_n = static_cast<std::int64_t>(max_count);
  IbInput in;
  in.points = torch::zeros({b, channels, big_n});
  in.mask = torch::zeros({b, big_n}, torch::kBool);
  float* points = in.points.data_ptr<float>();
  bool* mask = in.mask.data_ptr<bool>();
  std::vector<float> cloud;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    const std::size_t count = obs[i]->count();
    cloud.resize(static_cast<std::size_t>(channels) * count);
    NormalizePoints(*obs[i], m, n, cloud.data());
    for (std::int64_t c = 0; c < channels; ++c)
      std::copy_n(cloud.data() + c * count, count, points + (i * channels + c) * max_count);
    std::fill_n(mask + i * max_count, count, true);
  }
  return in;
}

torch::Tensor MakePositionTarget(const std::vector<Eigen::Vector3d>& positions_w,
                                 const IbNormalization& n) {
  torch::Tensor y = torch::empty({static_cast<std::int64_t>(positions_w.size()), 3});
  float* p = y.data_ptr<float>();
  for (std::size_t i = 0; i < positions_w.size(); ++i) {
    const Eigen::Vector3d q = NormalizePosition(positions_w[i], n);
    for (int a = 0; a < 3; ++a) p[3 * i + a] = static_cast<float>(q[a]);
  }
  return y;
}

ImageFeatureEncoderImpl::ImageFeatureEncoderImpl(double dropout, StereoBranches branches,
                                                 int eye_pool_side, bool roi_geometry)
    : branches_(branches), eye_pool_side_(eye_pool_side), roi_geometry_(roi_geometry) {
  if (eye_pool_side < 0 || (eye_pool_side > 0 && 32 % eye_pool_side != 0))
    throw std::invalid_argument(
        "ImageFeatureEncoder: eye_pool_side must be 0 or a divisor of 32, got " +
        std::to_string(eye_pool_side));
  using torch::nn::Conv2dOptions;
  const auto conv = [](std::int64_t in, std::int64_t out) {
    return torch::nn::Conv2d(Conv2dOptions(in, out, 3).stride(2).padding(1));
  };
  conv1_ = register_module("conv1", conv(1, 32));
  conv2_ = register_module("conv2", conv(32, 64));
  if (branches_ == StereoBranches::kTwo) {
    conv1_right_ = register_module("conv1_right", conv(1, 32));
    conv2_right_ = register_module("conv2_right", conv(32, 64));
  }
  if (eye_pool_side_ > 0)
    pool_ = register_module(
        "pool", torch::nn::AdaptiveAvgPool2d(torch::nn::AdaptiveAvgPool2dOptions(eye_pool_side_)));
  dropout_ = register_module("dropout", torch::nn::Dropout(dropout));
}

std::int64_t ImageFeatureEncoderImpl::eye_features() const {
  const std::int64_t side = eye_pool_side_ > 0 ? eye_pool_side_ : 32;
  return 64 * side * side;
}

std::int64_t ImageFeatureEncoderImpl::features() const {
  return 2 * eye_features() + (roi_geometry_ ? kCameraGeometryFeatures : 0);
}

std::vector<torch::Tensor> ImageFeatureEncoderImpl::FeatureMaps(const torch::Tensor& eyes,
                                                                bool right) {
  const bool own = right && branches_ == StereoBranches::kTwo;
  torch::nn::Conv2d& c1 = own ? conv1_right_ : conv1_;
  torch::nn::Conv2d& c2 = own ? conv2_right_ : conv2_;
  // Table I: ReLU(Conv 1->32) -> ReLU(Conv 32->64), 3x3, stride 2, padding 1.
  torch::Tensor h1 = torch::relu(c1->forward(eyes));
  torch::Tensor h2 = torch::relu(c2->forward(h1));
  return {h1, h2};
}

torch::Tensor ImageFeatureEncoderImpl::forward(const torch::Tensor& left,
                                               const torch::Tensor& right,
                                               const torch::Tensor& geometry) {
  constexpr std::int64_t kSide = CameraObservation::kCropPx;
  if (!HasShape(left, {-1, 1, kSide, kSide}))
    Fail("ImageFeatureEncoder: left", "[B, 1, 128, 128]", left);
  const std::int64_t b = left.size(0);
  if (!HasShape(right, {b, 1, kSide, kSide}))
    Fail("ImageFeatureEncoder: right", "[B, 1, 128, 128] with B = " + std::to_string(b), right);
  if (!HasShape(geometry, {b, kCameraGeometryFeatures}))
    Fail("ImageFeatureEncoder: geometry", "[B, 18] with B = " + std::to_string(b), geometry);
  // Flattened, 2 x 64x32x32 = 131072 features give each of the mu and sigma
  // MLPs 16.8 M first-layer weights (the paper's layout); a 4x4 average pool
  // keeps the coarse layout of each eye in 1024.
  const auto flat = [&](const torch::Tensor& maps) {
    return (pool_ ? pool_->forward(maps) : maps).flatten(1);
  };
  torch::Tensor h_left, h_right;
  if (branches_ == StereoBranches::kShared) {
    // Shared weights: one pass over both eyes as a batch of 2B.
    std::vector<torch::Tensor> eyes =
        flat(FeatureMaps(torch::cat({left, right}, 0)).back()).chunk(2, 0);
    h_left = eyes[0];
    h_right = eyes[1];
  } else {
    h_left = flat(FeatureMaps(left).back());
    h_right = flat(FeatureMaps(right, true).back());
  }
  // h^c = Dropout(Concat(h^left, h^right)) (paper eq. for h^c).
  torch::Tensor h_c = dropout_->forward(torch::cat({h_left, h_right}, 1));
  return roi_geometry_ ? torch::cat({h_c, geometry}, 1) : h_c;
}

PointNetEncoderImpl::PointNetEncoderImpl(std::int64_t in_channels, PointFrame frame, PointNorm norm)
    : in_channels_(in_channels), frame_(frame), norm_(norm) {
  if (in_channels < 1)
    throw std::invalid_argument("PointNetEncoder: in_channels must be >= 1, got " +
                                std::to_string(in_channels));
  if (frame == PointFrame::kCentroid && in_channels < 3)
    throw std::invalid_argument("PointNetEncoder: the centroid frame needs x, y, z channels");
  const std::int64_t widths[] = {64, 64, 64, 128, kFeatures};
  std::int64_t in = in_channels;
  for (int l = 0; l < 5; ++l) {
    const std::string k = std::to_string(l + 1);
    // No conv bias before a BatchNorm or GroupNorm: their shift absorbs it.
    convs_.push_back(register_module(
        "conv" + k,
        torch::nn::Conv1d(
            torch::nn::Conv1dOptions(in, widths[l], 1).bias(norm == PointNorm::kNone))));
    if (norm == PointNorm::kBatch)
      norms_.push_back(register_module("bn" + k, torch::nn::BatchNorm1d(widths[l])));
    if (norm == PointNorm::kGroup)
      group_norms_.push_back(register_module(
          "gn" + k, torch::nn::GroupNorm(torch::nn::GroupNormOptions(8, widths[l]))));
    in = widths[l];
  }
}

std::int64_t PointNetEncoderImpl::features() const {
  return kFeatures + (frame_ == PointFrame::kCentroid ? 3 : 0);
}

torch::Tensor PointNetEncoderImpl::PointFeatures(const torch::Tensor& x) {
  // The fold is computed without autograd: with gradients on (e.g. fine-tuning
  // with frozen statistics), take the modules' path so the weights get them.
  if (norm_ != PointNorm::kGroup && !is_training() && !torch::GradMode::is_enabled())
    return FoldedPointFeatures(x);
  if (norm_ == PointNorm::kGroup) {
    // Each point a sample of its own: [P, C, 1].
    torch::Tensor h = x.unsqueeze(2);
    for (std::size_t l = 0; l < convs_.size(); ++l)
      h = torch::relu(group_norms_[l]->forward(convs_[l]->forward(h)));
    return h.squeeze(2);
  }
  // Table I: H_l = ReLU(BN(Conv1d(H_{l-1}))), l = 1..5, on [1, C, P].
  torch::Tensor h = x.t().unsqueeze(0);
  for (std::size_t l = 0; l < convs_.size(); ++l) {
    h = convs_[l]->forward(h);
    h = torch::relu(norm_ == PointNorm::kBatch ? norms_[l]->forward(h) : h);
  }
  return h.squeeze(0).t();
}

torch::Tensor PointNetEncoderImpl::FoldedPointFeatures(torch::Tensor x) {
  // BN(W h) = s * (W h - mean) + beta with s = gamma / sqrt(var + eps), so
  // layer l is ReLU(W' h + b'), W' = diag(s) W, b' = beta - s * mean. One
  // matrix product per layer instead of a convolution and a BatchNorm pass.
  // Without a norm, W' = W and b' the conv's bias.
  if (folded_weight_.empty()) {
    torch::NoGradGuard no_grad;
    for (std::size_t l = 0; l < convs_.size(); ++l) {
      const torch::Tensor w = convs_[l]->weight.squeeze(2);
      if (norm_ == PointNorm::kNone) {
        folded_weight_.push_back(w.t().contiguous());
        folded_bias_.push_back(convs_[l]->bias);
        continue;
      }
      const auto& bn = norms_[l];
      const torch::Tensor s = bn->weight / (bn->running_var + bn->options.eps()).sqrt();
      folded_weight_.push_back((w * s.unsqueeze(1)).t().contiguous());
      folded_bias_.push_back(bn->bias - bn->running_mean * s);
    }
  }
  for (std::size_t l = 0; l < folded_weight_.size(); ++l)
    x = torch::addmm(folded_bias_[l], x, folded_weight_[l]).relu_();
  return x;
}

void PointNetEncoderImpl::train(bool on) {
  folded_weight_.clear();
  folded_bias_.clear();
  torch::nn::Module::train(on);
}

void PointNetEncoderImpl::load(torch::serialize::InputArchive& archive) {
  folded_weight_.clear();
  folded_bias_.clear();
  torch::nn::Module::load(archive);
}

torch::Tensor PointNetEncoderImpl::Pooled(const torch::Tensor& points, const torch::Tensor& mask) {
  const std::int64_t b = points.size(0);
  const std::int64_t n = points.size(2);
  const torch::Tensor rows = points.transpose(1, 2);  // [B, N, C]
  if (mask.all().item<bool>())
    return PointFeatures(rows.reshape({b * n, in_channels_})).reshape({b, n, kFeatures}).amax(1);

  // Pack the real points of all clouds into one sequence [P, C], so the
  // padding is never computed: it cannot enter the BatchNorm statistics or
  // win the max, whatever it holds.
  const torch::Tensor h = PointFeatures(rows.index({mask}));  // [P, 1024]
  torch::Tensor scattered =
      torch::full({b, n, kFeatures}, -std::numeric_limits<float>::infinity(), h.options());
  scattered.index_put_({mask}, h);
  return scattered.amax(1);  // MaxPool_global(H_5), over real points only
}

torch::Tensor PointNetEncoderImpl::forward(const torch::Tensor& points, const torch::Tensor& mask) {
  if (!HasShape(points, {-1, in_channels_, -1}))
    Fail("PointNetEncoder: points", "[B, " + std::to_string(in_channels_) + ", N]", points);
  const std::int64_t b = points.size(0);
  const std::int64_t n = points.size(2);
  if (!HasShape(mask, {b, n}) || mask.scalar_type() != torch::kBool)
    Fail("PointNetEncoder: mask",
         "a bool tensor [" + std::to_string(b) + ", " + std::to_string(n) + "]", mask);
  if (b == 0 || n == 0 || !mask.any(1).all().item<bool>())
    throw std::invalid_argument("PointNetEncoder: every cloud needs at least one real point");
  if (frame_ == PointFrame::kScene) return Pooled(points, mask);

  // Centroid frame: c = mean of the real points' x, y, z; the points relative to it.
  const torch::Tensor m = mask.unsqueeze(1).to(points.scalar_type());  // [B, 1, N]
  const torch::Tensor xyz = points.narrow(1, 0, 3);
  const torch::Tensor centroid = (xyz * m).sum(2) / m.sum(2);  // [B, 3]
  const torch::Tensor relative =
      torch::cat({xyz - centroid.unsqueeze(2), points.narrow(1, 3, in_channels_ - 3)}, 1);
  return torch::cat({Pooled(relative, mask), centroid}, 1);
}

IbHeadImpl::IbHeadImpl(std::int64_t in_features, std::int64_t latent_dim) {
  mu_mlp_ = register_module("mu_mlp", TwoLayerMlp(in_features, kHidden, latent_dim));
  sigma_mlp_ = register_module("sigma_mlp", TwoLayerMlp(in_features, kHidden, latent_dim));
}

IbHeadOutput IbHeadImpl::forward(const torch::Tensor& h) {
  IbHeadOutput out;
  out.mu = mu_mlp_->forward(h);
  // The -5 shift starts sigma near 0.007 (nearly deterministic codes early in
  // training); the 1e-6 floor keeps log sigma^2 finite.
  out.sigma = F::softplus(sigma_mlp_->forward(h) - 5.0) + 1e-6;
  // t = mu + sigma * eps, eps ~ N(0, I) (paper's reparameterisation trick).
  out.t = is_training() ? out.mu + out.sigma * torch::randn_like(out.sigma) : out.mu;
  return out;
}

std::int64_t MlpCompressorImpl::MatchedHidden(std::int64_t in_features, std::int64_t latent_dim) {
  // Solve (d + 1 + z) H + z = 2 P_layer(d, 128, z) for H and round.
  const std::int64_t target = 2 * TwoLayerParameters(in_features, IbHeadImpl::kHidden, latent_dim);
  const double h =
      static_cast<double>(target - latent_dim) / static_cast<double>(in_features + 1 + latent_dim);
  return std::max<std::int64_t>(1, std::llround(h));
}

MlpCompressorImpl::MlpCompressorImpl(std::int64_t in_features, std::int64_t latent_dim) {
  mlp_ = register_module(
      "mlp", TwoLayerMlp(in_features, MatchedHidden(in_features, latent_dim), latent_dim));
}

IbHeadOutput MlpCompressorImpl::forward(const torch::Tensor& h) {
  IbHeadOutput out;
  out.mu = mlp_->forward(h);
  out.t = out.mu;
  return out;
}

IbDecoderImpl::IbDecoderImpl(std::int64_t latent_dim, double dropout) {
  mlp_ = register_module(
      "mlp", torch::nn::Sequential(torch::nn::Linear(latent_dim, 128), torch::nn::ReLU(),
                                   torch::nn::Dropout(dropout), torch::nn::Linear(128, 64),
                                   torch::nn::ReLU(), torch::nn::Linear(64, 3)));
}

torch::Tensor IbDecoderImpl::forward(const torch::Tensor& t) { return mlp_->forward(t); }

torch::Tensor KlDivergence(const torch::Tensor& mu, const torch::Tensor& sigma) {
  if (!mu.defined() || !sigma.defined() || !mu.sizes().equals(sigma.sizes()))
    throw std::invalid_argument("KlDivergence: mu and sigma must have the same shape, got " +
                                ShapeOf(mu) + " and " + ShapeOf(sigma));
  // D_KL = 1/2 sum_j (mu_j^2 + sigma_j^2 - log sigma_j^2 - 1) (paper eq. for D_KL).
  return 0.5 * (mu.square() + sigma.square() - 2.0 * sigma.log() - 1.0).sum(-1);
}

IbCcModelImpl::IbCcModelImpl(const IbCcConfig& config) : config_(config) {
  if (config.latent_dim < 1)
    throw std::invalid_argument("IbCcModel: latent_dim must be >= 1, got " +
                                std::to_string(config.latent_dim));
  if (!(config.dropout >= 0.0 && config.dropout < 1.0))
    throw std::invalid_argument("IbCcModel: dropout must be in [0, 1), got " +
                                std::to_string(config.dropout));
  if (config.modality == Modality::kCamera) {
    image_encoder_ = register_module(
        "image_encoder", ImageFeatureEncoder(config.dropout, config.stereo_branches,
                                             config.eye_pool_side, config.roi_geometry));
    feature_dim_ = image_encoder_->features();
  } else {
    point_encoder_ = register_module(
        "point_encoder",
        PointNetEncoder(PointChannels(config.modality), config.point_frame, config.point_norm));
    feature_dim_ = point_encoder_->features();
  }
  if (config.bottleneck == IbBottleneck::kIb)
    ib_head_ = register_module("ib_head", IbHead(feature_dim_, config.latent_dim));
  else
    mlp_compressor_ =
        register_module("mlp_compressor", MlpCompressor(feature_dim_, config.latent_dim));
  decoder_ = register_module("decoder", IbDecoder(config.latent_dim, config.dropout));
}

torch::Tensor IbCcModelImpl::Features(const IbInput& in) {
  if (image_encoder_) return image_encoder_->forward(in.left, in.right, in.geometry);
  return point_encoder_->forward(in.points, in.mask);
}

IbHeadOutput IbCcModelImpl::Bottleneck(const torch::Tensor& h) {
  return ib_head_ ? ib_head_->forward(h) : mlp_compressor_->forward(h);
}

IbOutput IbCcModelImpl::forward(const IbInput& in) {
  IbOutput out;
  out.features = Features(in);
  IbHeadOutput head = Bottleneck(out.features);
  out.mu = head.mu;
  out.sigma = head.sigma;
  out.t = head.t;
  out.y_hat = decoder_->forward(out.t);
  return out;
}

torch::Tensor IbCcModelImpl::Encode(const IbInput& in) { return Bottleneck(Features(in)).mu; }

torch::Tensor IbCcModelImpl::Decode(const torch::Tensor& t) {
  if (!HasShape(t, {-1, config_.latent_dim}))
    Fail("IbCcModel::Decode", "[B, " + std::to_string(config_.latent_dim) + "]", t);
  return decoder_->forward(t);
}

IbLoss IbCcModelImpl::Loss(const IbOutput& out, const torch::Tensor& y) const {
  if (!HasShape(y, {out.y_hat.size(0), 3}))
    Fail("IbCcModel::Loss: target", "[" + std::to_string(out.y_hat.size(0)) + ", 3]", y);
  IbLoss loss;
  // L_MSE = ||y - y_hat||_2^2 (paper), averaged over the batch; in m^2 or
  // in normalised units (IbMseUnits).
  const double scale = config_.mse_units == IbMseUnits::kMetres
                           ? config_.normalization.scale_m * config_.normalization.scale_m
                           : 1.0;
  loss.mse = (out.y_hat - y).square().sum(1).mean() * scale;
  loss.kl = out.sigma.defined() ? KlDivergence(out.mu, out.sigma).mean()
                                : torch::zeros({}, out.y_hat.options());
  // L_ALL = L_MSE + beta * D_KL (paper eq. for L_ALL).
  loss.total = loss.mse + config_.beta * loss.kl;
  return loss;
}

std::int64_t IbCcModelImpl::BottleneckParameterCount() const {
  return ib_head_ ? ParameterCount(*ib_head_) : ParameterCount(*mlp_compressor_);
}

std::int64_t ParameterCount(const torch::nn::Module& m) {
  std::int64_t n = 0;
  for (const torch::Tensor& p : m.parameters()) n += p.numel();
  return n;
}

}  // namespace uavsim::pipeline
