#include "pipeline/edge/uavloc_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_io.h"
#include "core/zip_check.h"

namespace uavsim::pipeline {

using core::Rule;

template <class V>
void Visit(V& v, UavLocModelConfig& c) {
  v("format", c.format);
  v.Check(c.format == kUavLocModelFormat, "format",
          "expected \"" + std::string(kUavLocModelFormat) + "\", got \"" + c.format + "\"");
  v("latent_dim", c.latent_dim, Rule::Range(2, 4096));
  v.Check(c.latent_dim % 2 == 0, "latent_dim",
          "expected an even size (sine-cosine pairs), got " + std::to_string(c.latent_dim));
  v("window_s", c.window_s, Rule::Range(1e-9, 3600.0));
  v("kappa", c.kappa, Rule{1.0, std::numeric_limits<double>::infinity(), true, false});
  v("time_unit_s", c.time_unit_s, Rule::Positive());
  v.Enum("tau_origin", c.tau_origin,
         std::vector<std::pair<const char*, TauOrigin>>{{"window", TauOrigin::kWindow},
                                                        {"clock", TauOrigin::kClock}});
  v.Enum("alignment", c.alignment, AlignmentNames());
  v.Enum("fusion", c.fusion, FusionKindNames());
  v("madw", c.madw);
  v("mica", c.mica);
  v.Check(c.fusion == FusionKind::kUavLoc || (c.madw && c.mica), "madw",
          "MADW and MICA are the paper's fusion: a fusion baseline needs both true");
  v.Check(c.fusion == FusionKind::kUavLoc || !c.anchored, "anchored",
          "the anchored head extends the paper's fusion only");
  v("score_hidden", c.score_hidden, Rule::Range(1, 65536));
  v("lambda_init", c.lambda_init);
  v("d_model", c.d_model, Rule::Range(1, 65536));
  v("layers", c.layers, Rule::Range(1, 256));
  v("d_state", c.d_state, Rule::Range(1, 4096));
  v("d_conv", c.d_conv, Rule::Range(1, 256));
  v("expand", c.expand, Rule::Range(1, 64));
  v.Enum("temporal", c.temporal, TemporalKindNames());
  v("tcn_kernel", c.tcn_kernel, Rule::Range(2, 64));
  v("anchored", c.anchored);
  v("anchor_features", c.anchor_features);
  v("candidate_offset_m", c.candidate_offset_m,
    Rule::Range(-UavLocModelConfig::kMaxCandidateOffset_m,
                UavLocModelConfig::kMaxCandidateOffset_m),
    0, kAnchorCandidates);
  v.Check(c.candidate_offset_m.empty() || c.candidate_offset_m.size() == kAnchorCandidates,
          "candidate_offset_m",
          "expected none or " + std::to_string(kAnchorCandidates) + " offsets, got " +
              std::to_string(c.candidate_offset_m.size()));
  v("position_centre_m", c.position_centre_m);
  v("position_scale_m", c.position_scale_m, Rule::Positive());
}
UAVSIM_INSTANTIATE_VISIT(UavLocModelConfig);

TeAlignConfig UavLocModelConfig::te_align() const {
  TeAlignConfig t;
  t.latent_dim = latent_dim;
  t.window_s = window_s;
  t.kappa = kappa;
  t.time_unit_s = time_unit_s;
  t.tau_origin = tau_origin;
  t.alignment = alignment;
  return t;
}

TemporalRegressorOptions UavLocModelConfig::regressor() const {
  MambaRegressorOptions r;
  r.input_dim = fused_dim();  // Eq. (26): the concatenation
  r.output_dim = 3;
  if (anchored) r.input_dim += kAnchorFeatures, r.output_dim = UavLocModelImpl::kHypotheses + 3 + 1;
  r.layers = layers;
  r.mamba.d_model = d_model;
  r.mamba.d_state = d_state;
  r.mamba.d_conv = d_conv;
  r.mamba.expand = expand;
  // Sec. VI, Fig. 11: the baselines in the Mamba's place, of its size.
  return MatchedTemporalOptions(temporal, r, tcn_kernel);
}

int UavLocModelConfig::fused_dim() const {
  switch (fusion) {
    case FusionKind::kLate:
      return latent_dim;
    case FusionKind::kHemis:
      return 2 * HemisEmbedding(latent_dim);
    default:
      return kModalityCount * latent_dim;
  }
}

void UavLocModelConfig::Validate() const {
  if (format != kUavLocModelFormat)
    throw std::invalid_argument("UavLocModel: format \"" + format + "\" is not \"" +
                                kUavLocModelFormat + "\"");
  te_align().Validate();
  regressor().Validate();
  if (fusion != FusionKind::kUavLoc && !(madw && mica))
    throw std::invalid_argument("UavLocModel: madw and mica are the paper's fusion; fusion " +
                                std::string(FusionKindName(fusion)) + " needs both true");
  if (fusion != FusionKind::kUavLoc && anchored)
    throw std::invalid_argument("UavLocModel: the anchored head extends the paper's fusion only");
  if (score_hidden < 1)
    throw std::invalid_argument("UavLocModel: score_hidden (" + std::to_string(score_hidden) +
                                ") must be >= 1");
  if (!std::isfinite(lambda_init))
    throw std::invalid_argument("UavLocModel: lambda_init must be finite");
  if (anchored && anchor_features != kAnchorFeatures)
    throw std::invalid_argument(
        "UavLocModel: an anchored head with " + std::to_string(anchor_features) +
        " anchor features (this build's has " + std::to_string(kAnchorFeatures) +
        "): train the model again (uavsim train)");
  if (!candidate_offset_m.empty() && candidate_offset_m.size() != kAnchorCandidates)
    throw std::invalid_argument("UavLocModel: candidate_offset_m must have none or " +
                                std::to_string(kAnchorCandidates) + " offsets, got " +
                                std::to_string(candidate_offset_m.size()));
  for (const Eigen::Vector3d& o : candidate_offset_m)
    if (!(o.array().abs() <= kMaxCandidateOffset_m).all())
      throw std::invalid_argument("UavLocModel: candidate offsets must be finite and within " +
                                  core::FormatNumber(kMaxCandidateOffset_m) + " m per axis");
  if (!position_centre_m.allFinite() || !std::isfinite(position_scale_m) || position_scale_m <= 0.0)
    throw std::invalid_argument(
        "UavLocModel: position_centre_m must be finite and position_scale_m finite and > 0, got " +
        core::FormatNumber(position_scale_m));
}

namespace {

const UavLocModelConfig& Validated(const UavLocModelConfig& config) {
  config.Validate();
  return config;
}

}  // namespace

UavLocModelImpl::UavLocModelImpl(const UavLocModelConfig& config)
    : config_(Validated(config)),
      te_align_(config.te_align()),
      tracker_(config.window_s, config.position_centre_m, config.position_scale_m) {
  const int z = config_.latent_dim;
  switch (config_.fusion) {
    case FusionKind::kUavLoc:
      if (config_.madw)
        madw = register_module("madw", Madw(kModalityCount, z, config_.score_hidden));
      if (config_.mica)
        mica = register_module("mica",
                               Mica(kModalityCount, z, config_.score_hidden, config_.lambda_init));
      break;
    case FusionKind::kEarly:
    case FusionKind::kHemis: {
      const int out = config_.fusion == FusionKind::kEarly ? z : HemisEmbedding(z);
      projections = register_module("projections", torch::nn::ModuleList());
      for (int m = 0; m < kModalityCount; ++m) projections->push_back(torch::nn::Linear(z, out));
      break;
    }
    case FusionKind::kLate:
      break;
  }
  if (config_.fusion == FusionKind::kLate) {
    branches = register_module("branches", torch::nn::ModuleList());
    for (int m = 0; m < kModalityCount; ++m)
      branches->push_back(TemporalRegressor(config_.regressor()));
    late_logits = register_parameter("late_logits", torch::zeros({kModalityCount}));
  } else {
    regressor = register_module("regressor", TemporalRegressor(config_.regressor()));
  }
  ResetState();
}

torch::Tensor UavLocModelImpl::LateCombine(const torch::Tensor& positions,
                                           const torch::Tensor& mask) const {
  // Decision-level fusion: softmax of the learnable weights over the
  // modalities available (MaskedSoftmax: 0 weight for missing ones).
  const torch::Tensor w = MaskedSoftmax(late_logits.expand_as(mask), mask, -1);
  return (w.unsqueeze(-1) * positions).sum(-2);
}

torch::Tensor UavLocModelImpl::Fuse(const torch::Tensor& latents, const torch::Tensor& mask) {
  const torch::Tensor present = mask.unsqueeze(-1);
  switch (config_.fusion) {
    case FusionKind::kUavLoc: {
      torch::Tensor x = madw ? madw(latents, mask).weighted : latents * present;  // Eq. (23)
      if (mica) x = mica(x, mask).fused;                                          // Eq. (25)
      // Eq. (26): t^f(k) = [t^{c,f}(k), t^{l,f}(k), t^{r,f}(k)].
      return x.flatten(1);
    }
    case FusionKind::kEarly: {
      std::vector<torch::Tensor> parts;
      for (int m = 0; m < kModalityCount; ++m)
        parts.push_back(
            torch::relu(projections[static_cast<std::size_t>(m)]->as<torch::nn::Linear>()->forward(
                latents.select(1, m))) *
            present.select(1, m));
      return torch::cat(parts, 1);
    }
    case FusionKind::kHemis: {
      std::vector<torch::Tensor> parts;
      for (int m = 0; m < kModalityCount; ++m)
        parts.push_back(
            torch::relu(projections[static_cast<std::size_t>(m)]->as<torch::nn::Linear>()->forward(
                latents.select(1, m))));
      const torch::Tensor e = torch::stack(parts, 1);  // [N, M, d]
      // Mean and (population) variance over the available modalities; 0
      // where none is.
      const torch::Tensor n = mask.sum(1, true).clamp_min(1.0).unsqueeze(-1);  // [N, 1, 1]
      const torch::Tensor mean = (e * present).sum(1, true) / n;
      const torch::Tensor var = ((e - mean).square() * present).sum(1) / n.squeeze(1);
      return torch::cat({mean.squeeze(1), var}, 1);
    }
    case FusionKind::kLate:
      break;
  }
  return latents * present;
}

torch::Tensor UavLocModelImpl::forward(const torch::Tensor& latents, const torch::Tensor& mask,
                                       const AnchorBatch* anchors, torch::Tensor* log_weights,
                                       torch::Tensor* hypotheses) {
  const int64_t z = config_.latent_dim;
  TORCH_CHECK(latents.dim() == 4 && latents.size(2) == kModalityCount && latents.size(3) == z,
              "UavLocModel: latents must be [B, K, ", kModalityCount, ", ", z, "], got ",
              latents.sizes());
  TORCH_CHECK(mask.dim() == 3 && mask.size(0) == latents.size(0) &&
                  mask.size(1) == latents.size(1) && mask.size(2) == kModalityCount,
              "UavLocModel: mask must be [B, K, ", kModalityCount, "], got ", mask.sizes());
  const int64_t batch = latents.size(0);
  const int64_t windows = latents.size(1);
  const torch::Tensor flat_mask =
      mask.reshape({batch * windows, kModalityCount}).to(latents.dtype());
  torch::Tensor fused = Fuse(latents.reshape({batch * windows, kModalityCount, z}), flat_mask);
  if (config_.fusion == FusionKind::kLate) {
    // Each modality's branch on its own latents, then the decision weights.
    fused = fused.reshape({batch, windows, kModalityCount, z});
    std::vector<torch::Tensor> positions;
    for (int m = 0; m < kModalityCount; ++m)
      positions.push_back(branches[static_cast<std::size_t>(m)]->as<TemporalRegressor>()->forward(
          fused.select(2, m)));
    return LateCombine(torch::stack(positions, 2),
                       flat_mask.reshape({batch, windows, kModalityCount}));
  }
  fused = fused.reshape({batch, windows, config_.fused_dim()});
  if (!config_.anchored) return regressor(fused);
  TORCH_CHECK(anchors != nullptr, "UavLocModel: an anchored model needs the windows' anchors");
  TORCH_CHECK(anchors->features.sizes() ==
                  torch::IntArrayRef({batch, windows, static_cast<int64_t>(kAnchorFeatures)}),
              "UavLocModel: anchor features must be [B, K, ", kAnchorFeatures, "], got ",
              anchors->features.sizes());
  return Anchored(regressor(torch::cat({fused, anchors->features}, 2)), anchors->candidates,
                  anchors->valid, anchors->ray, log_weights, hypotheses);
}

torch::Tensor UavLocModelImpl::Anchored(const torch::Tensor& head, const torch::Tensor& candidates,
                                        const torch::Tensor& valid, const torch::Tensor& ray,
                                        torch::Tensor* log_weights,
                                        torch::Tensor* hypotheses) const {
  const int64_t c = kAnchorCandidates;
  TORCH_CHECK(candidates.dim() == head.dim() + 1 && candidates.size(-2) == c &&
                  candidates.size(-1) == 3 && valid.size(-1) == c,
              "UavLocModel: anchor candidates must be [..., ", c, ", 3], got ", candidates.sizes());
  TORCH_CHECK(ray.dim() == head.dim() && ray.size(-1) == 7,
              "UavLocModel: anchor rays must be [..., 7], got ", ray.sizes());
  // The free hypotheses: the held ray's point at the learned range (allowed
  // when a ray is held) and the learned absolute position (always).
  const torch::Tensor ray_valid = ray.narrow(-1, 0, 1);
  const torch::Tensor on_ray =
      ray.narrow(-1, 1, 3) + torch::softplus(head.narrow(-1, c + 5, 1)) * ray.narrow(-1, 4, 3);
  const torch::Tensor allowed = torch::cat({valid, ray_valid, torch::ones_like(ray_valid)}, -1);
  const torch::Tensor logits = head.narrow(-1, 0, kHypotheses);
  const torch::Tensor log_w = torch::log_softmax(
      logits.masked_fill(allowed < 0.5, -std::numeric_limits<float>::infinity()), -1);
  // [..., C + 2, 3]; a ray-less window's on-ray point is only the origin
  // row of zeros, weighed 0.
  const torch::Tensor h =
      torch::cat({CorrectedCandidates(candidates), (on_ray * ray_valid).unsqueeze(-2),
                  head.narrow(-1, c + 2, 3).unsqueeze(-2)},
                 -2);
  if (log_weights) *log_weights = log_w;
  if (hypotheses) *hypotheses = h;
  return (log_w.exp().unsqueeze(-1) * h).sum(-2);
}

torch::Tensor UavLocModelImpl::CorrectedCandidates(const torch::Tensor& candidates) const {
  if (config_.candidate_offset_m.empty()) return candidates;
  std::array<float, 3 * kAnchorCandidates> offset;
  for (std::size_t c = 0; c < kAnchorCandidates; ++c)
    for (std::size_t j = 0; j < 3; ++j)
      offset[3 * c + j] = static_cast<float>(config_.candidate_offset_m[c][static_cast<int>(j)] /
                                             config_.position_scale_m);
  return candidates -
         torch::from_blob(offset.data(), {kAnchorCandidates, 3}).to(candidates.dtype());
}

void UavLocModelImpl::ResetRegressors() {
  if (regressor) state_ = regressor->InitialState(1);
  branch_states_.clear();
  if (branches)
    for (const auto& b : *branches)
      branch_states_.push_back(b->as<TemporalRegressor>()->InitialState(1));
}

void UavLocModelImpl::ResetState() {
  ResetRegressors();
  last_window_.reset();
  tracker_.Reset();
  last_anchors_ = {};
}

torch::Tensor UavLocModelImpl::StepAligned(const AlignedWindow& window,
                                           const AnchorWindow& anchors) {
  const int64_t z = config_.latent_dim;
  torch::Tensor latents = torch::empty({1, kModalityCount, z});
  torch::Tensor mask = torch::empty({1, kModalityCount});
  float* latent_data = latents.data_ptr<float>();
  float* mask_data = mask.data_ptr<float>();
  for (int m = 0; m < kModalityCount; ++m) {
    const std::vector<float>& t = window.latent[static_cast<std::size_t>(m)];
    std::copy(t.begin(), t.end(), latent_data + m * z);
    mask_data[m] = window.mask[static_cast<std::size_t>(m)];
  }
  if (config_.fusion == FusionKind::kLate) {
    const torch::Tensor masked = Fuse(latents, mask);  // [1, M, z]
    std::vector<torch::Tensor> positions;
    for (int m = 0; m < kModalityCount; ++m)
      positions.push_back(branches[static_cast<std::size_t>(m)]->as<TemporalRegressor>()->Step(
          masked.select(1, m), &branch_states_[static_cast<std::size_t>(m)]));
    return LateCombine(torch::stack(positions, 1), mask);
  }
  if (!config_.anchored) return regressor->Step(Fuse(latents, mask), &state_);
  const AnchorBatch a = StackAnchors({{anchors}});
  const torch::Tensor x = torch::cat({Fuse(latents, mask), a.features[0]}, 1);
  return Anchored(regressor->Step(x, &state_), a.candidates[0], a.valid[0], a.ray[0]);
}

Eigen::Vector3d UavLocModelImpl::Step(const WindowInputs& window) {
  if (last_window_ && window.window <= *last_window_)
    throw std::invalid_argument("UavLocModel::Step: window " + std::to_string(window.window) +
                                " does not follow window " + std::to_string(*last_window_));
  // Align first: bad input throws before the state changes.
  const AlignedWindow aligned = te_align_.Align(window);
  c10::InferenceMode inference;
  if (last_window_) {
    const std::int64_t gap = window.window - *last_window_ - 1;
    if (gap > kMaxGapWindows) {
      ResetRegressors();
    } else {
      AlignedWindow empty;
      for (auto& t : empty.latent) t.assign(static_cast<std::size_t>(config_.latent_dim), 0.0f);
      for (std::int64_t g = 0; g < gap; ++g) {
        empty.window = *last_window_ + 1 + g;
        StepAligned(empty, tracker_.Update(empty.window, WindowAnchors{}));
      }
    }
  }
  if (last_window_ && window.window - *last_window_ - 1 > kMaxGapWindows) tracker_.Reset();
  last_window_ = window.window;
  last_anchors_ = tracker_.Update(window.window, te_align_.AnchorsOf(window));
  const torch::Tensor p = PositionInMetres(StepAligned(aligned, last_anchors_)).to(torch::kFloat64);
  const double* d = p.data_ptr<double>();
  return {d[0], d[1], d[2]};
}

torch::Tensor UavLocModelImpl::NormalizePosition(const torch::Tensor& position_m) const {
  const Eigen::Vector3d& c = config_.position_centre_m;
  const torch::Tensor centre =
      torch::tensor({c.x(), c.y(), c.z()}, position_m.options().dtype(torch::kFloat64))
          .to(position_m.dtype());
  return (position_m - centre) / config_.position_scale_m;
}

torch::Tensor UavLocModelImpl::PositionInMetres(const torch::Tensor& normalized) const {
  const Eigen::Vector3d& c = config_.position_centre_m;
  const torch::Tensor centre =
      torch::tensor({c.x(), c.y(), c.z()}, normalized.options().dtype(torch::kFloat64))
          .to(normalized.dtype());
  return normalized * config_.position_scale_m + centre;
}

void UavLocModelImpl::SetPositionNormalization(const Eigen::Vector3d& centre_m, double scale_m) {
  UavLocModelConfig c = config_;
  c.position_centre_m = centre_m;
  c.position_scale_m = scale_m;
  c.Validate();
  config_ = c;
  tracker_ = AnchorTracker(c.window_s, centre_m, scale_m);
}

FusionBatch StackWindows(const std::vector<std::vector<AlignedWindow>>& sequences) {
  if (sequences.empty() || sequences.front().empty())
    throw std::invalid_argument("StackWindows: need at least one non-empty sequence");
  const std::size_t windows = sequences.front().size();
  const std::size_t z = sequences.front().front().latent[0].size();
  const std::size_t m_count = static_cast<std::size_t>(kModalityCount);
  FusionBatch batch;
  const auto b = static_cast<int64_t>(sequences.size());
  const auto k = static_cast<int64_t>(windows);
  batch.latents = torch::empty({b, k, kModalityCount, static_cast<int64_t>(z)});
  batch.mask = torch::empty({b, k, kModalityCount});
  float* l = batch.latents.data_ptr<float>();
  float* mk = batch.mask.data_ptr<float>();
  for (std::size_t s = 0; s < sequences.size(); ++s) {
    if (sequences[s].size() != windows)
      throw std::invalid_argument("StackWindows: sequence " + std::to_string(s) + " has " +
                                  std::to_string(sequences[s].size()) +
                                  " windows, sequence 0 has " + std::to_string(windows));
    for (std::size_t w = 0; w < windows; ++w) {
      const AlignedWindow& a = sequences[s][w];
      for (std::size_t m = 0; m < m_count; ++m) {
        if (a.latent[m].size() != z)
          throw std::invalid_argument("StackWindows: latent size " +
                                      std::to_string(a.latent[m].size()) + " in sequence " +
                                      std::to_string(s) + ", expected " + std::to_string(z));
        std::copy(a.latent[m].begin(), a.latent[m].end(),
                  l + ((s * windows + w) * m_count + m) * z);
        mk[(s * windows + w) * m_count + m] = a.mask[m];
      }
    }
  }
  return batch;
}

AnchorBatch StackAnchors(const std::vector<std::vector<AnchorWindow>>& sequences) {
  if (sequences.empty() || sequences.front().empty())
    throw std::invalid_argument("StackAnchors: need at least one non-empty sequence");
  const auto b = static_cast<int64_t>(sequences.size());
  const auto k = static_cast<int64_t>(sequences.front().size());
  const int64_t c = kAnchorCandidates;
  AnchorBatch out;
  out.features = torch::empty({b, k, kAnchorFeatures});
  out.candidates = torch::empty({b, k, c, 3});
  out.valid = torch::empty({b, k, c});
  out.ray = torch::empty({b, k, 7});
  float* f = out.features.data_ptr<float>();
  float* p = out.candidates.data_ptr<float>();
  float* v = out.valid.data_ptr<float>();
  float* r = out.ray.data_ptr<float>();
  for (const std::vector<AnchorWindow>& seq : sequences) {
    if (static_cast<int64_t>(seq.size()) != k)
      throw std::invalid_argument("StackAnchors: sequences differ in length");
    for (const AnchorWindow& w : seq) {
      f = std::copy(w.features.begin(), w.features.end(), f);
      r = std::copy(w.ray.begin(), w.ray.end(), r);
      for (int i = 0; i < c; ++i) {
        for (int j = 0; j < 3; ++j) *p++ = static_cast<float>(w.candidates[i][j]);
        *v++ = w.valid[i];
      }
    }
  }
  return out;
}

std::string SidecarPath(const std::string& path) { return path + ".json"; }

namespace {

// The first line of a LibTorch error, without its C++ backtrace.
std::string Brief(const c10::Error& e) {
  std::string s = e.what_without_backtrace();
  return s.substr(0, s.find('\n'));
}

}  // namespace

void SaveUavLocModel(const UavLocModel& model, const std::string& path) {
  try {
    core::WriteViaTemporary(path, [&](const std::string& temp) { torch::save(model, temp); });
  } catch (const c10::Error& e) {
    throw std::runtime_error(path + ": cannot write model weights: " + Brief(e));
  }
  core::WriteFileAtomic(SidecarPath(path), core::ToJson(model->config()).dump(2) + "\n");
}

UavLocModel LoadUavLocModel(const std::string& path) {
  const std::string sidecar = SidecarPath(path);
  UavLocModelConfig config;
  const core::Json json = core::LoadJsonFile(sidecar);
  core::FromJson(json, sidecar, "", config);
  // Anchored models from before the key existed had 41 features.
  if (config.anchored && !json.contains("anchor_features")) config.anchor_features = 41;
  try {
    config.Validate();
  } catch (const std::invalid_argument& e) {
    throw core::ConfigError(sidecar, "", e.what());
  }
  UavLocModel model(config);
  // torch::load replaces each tensor whatever its shape, so the shapes the
  // configuration implies are checked afterwards.
  std::map<std::string, std::vector<int64_t>> expected;
  for (const auto& item : model->named_parameters())
    expected[item.key()] = item.value().sizes().vec();
  for (const auto& item : model->named_buffers()) expected[item.key()] = item.value().sizes().vec();
  if (!std::filesystem::is_regular_file(path))
    throw core::ConfigError(path, "", "model weights file not found");
  core::RequireWholeZip(path);  // a truncated file says so (issue 43)
  try {
    torch::load(model, path);
  } catch (const c10::Error& e) {
    throw core::ConfigError(path, "",
                            "not UAVLoc model weights matching " + sidecar + ": " + Brief(e));
  }
  for (const auto& item : model->named_parameters()) {
    if (item.value().sizes().vec() != expected[item.key()])
      throw core::ConfigError(
          path, "", "weights \"" + item.key() + "\" do not have the shape " + sidecar + " implies");
  }
  model->ResetState();
  return model;
}

}  // namespace uavsim::pipeline
