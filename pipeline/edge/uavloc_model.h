// The edge server's UAVLoc network (paper Sec. V, Fig. "data processing
// network"): TE-Align -> MADW -> MICA -> concatenation [t^{c,f}, t^{l,f},
// t^{r,f}] -> Mamba -> linear head -> 3-D position. The temporal regressor
// is the paper's Mamba or, as data (`temporal`), one of the GRU, LSTM and TCN
// it is compared against in Sec. VI, Fig. 11 (temporal_regressor.h).
//
// Training runs forward() on batches of window sequences already aligned by
// TeAlign (StackWindows); online use calls Step() once per window and keeps
// the regressor's state between calls. The network predicts the position
// normalised as (p - centre) / scale (scale isotropic, so the normalised MSE
// is the paper's L^loc of Eq. (28) up to the constant 1/scale^2); centre and
// scale are part of the configuration.
//
// Files: Save() writes the LibTorch archive of the weights at `path` and the
// configuration as JSON at SidecarPath(path), each written to a temporary
// name and renamed. Load() reads both; a bad sidecar is a core::ConfigError
// naming the file and JSON pointer, bad or mismatched weights a
// core::ConfigError naming the weights file.
#pragma once

#include <torch/torch.h>

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/anchored/anchors.h"
#include "pipeline/edge/fusion_kind.h"
#include "pipeline/edge/madw.h"
#include "pipeline/edge/mica.h"
#include "pipeline/edge/te_align.h"
#include "pipeline/edge/temporal_regressor.h"

namespace uavsim::pipeline {

inline constexpr const char* kUavLocModelFormat = "uavloc-model/1";

struct UavLocModelConfig {
  std::string format = kUavLocModelFormat;
  // TE-Align (see TeAlignConfig).
  int latent_dim = 16;  // z of every modality
  double window_s = 0.2;
  double kappa = 10000.0;
  double time_unit_s = 1e-3;
  TauOrigin tau_origin = TauOrigin::kWindow;  // absent from older sidecars: kWindow
  // TE-Align or a resampling baseline (Fig. 12; absent: TE-Align).
  Alignment alignment = Alignment::kTeAlign;
  // The fusion (fusion_kind.h; absent: the paper's), and with it MADW and
  // MICA each switchable (Fig. 13; off: t^{m,w} = t^{m,e} masked, and
  // t^{m,f} = t^{m,w}). Only the paper's fusion has them: the baselines
  // need both true.
  FusionKind fusion = FusionKind::kUavLoc;
  bool madw = true;
  bool mica = true;
  // MADW and MICA (Table I: MLP_128; paper Sec. VI: λ initialised to 0.5).
  int score_hidden = 128;
  double lambda_init = 0.5;
  // Mamba (the paper is silent; DESIGN.md: d_state 16, d_conv 4, expand 2).
  int d_model = 64;
  int layers = 2;
  int d_state = 16;
  int d_conv = 4;
  int expand = 2;
  // The temporal regressor (absent from older sidecars: kMamba). The GRU,
  // LSTM and TCN take `layers` and the width that matches the Mamba's
  // parameter count at the sizes above (MatchedTemporalOptions); the TCN's
  // kernel is tcn_kernel (absent: 3), its dilations 1, 2, 4, ...
  TemporalKind temporal = TemporalKind::kMamba;
  int tcn_kernel = 3;
  // The paper's head regresses the position from the Mamba output alone.
  // Anchored (pipeline/anchored/anchors.h): the anchor features join t^f at the Mamba
  // input, and the head gives logits over the window's valid candidates c_i
  // and two free hypotheses: the held camera ray's point at a learned range
  // t, f = o + t d (t = softplus; allowed when a ray is held), and a
  // learned absolute position a (the paper head's regression; always
  // allowed):
  //   p = sum_i w_i c_i + w_f f + w_a a,  w = softmax over the allowed ones.
  // (Why two free hypotheses and no learned residual per candidate: chosen
  // on training episodes, see NOTES.md.)
  bool anchored = false;
  // The anchor features the model was trained with: must be this build's
  // kAnchorFeatures (41 for the first anchored head, with the residual; 47
  // before the filter's track: such models need training again).
  int anchor_features = kAnchorFeatures;
  // Anchored head: each candidate's offset from the target's reference
  // point in metres, subtracted before the head weighs it (the trainer's
  // MedianCandidateOffsets on the training episodes); empty: none, else
  // kAnchorCandidates of them.
  std::vector<Eigen::Vector3d> candidate_offset_m;
  static constexpr double kMaxCandidateOffset_m = 1.0;  // per axis
  // Output normalisation: the head predicts (p - centre) / scale, p in
  // world ENU metres.
  Eigen::Vector3d position_centre_m = Eigen::Vector3d::Zero();
  double position_scale_m = 1.0;

  TeAlignConfig te_align() const;
  // The regressor after the fusion (late fusion: each modality's branch).
  TemporalRegressorOptions regressor() const;
  // The fusion's output per window: the regressor's input before any anchor
  // features (late fusion: one modality's latent, z).
  int fused_dim() const;
  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

template <class V>
void Visit(V& v, UavLocModelConfig& c);

class UavLocModelImpl : public torch::nn::Module {
 public:
  // Validates `config` (std::invalid_argument). Weights are drawn from
  // LibTorch's global generator: the same torch::manual_seed gives the same
  // model.
  explicit UavLocModelImpl(const UavLocModelConfig& config);

  // latents: t^{m,e}(k) [B, K, M, z] (M = 3 in Modality order); mask:
  // [B, K, M], 1 available, 0 missing; anchors (anchored models only, else
  // ignored): the windows' AnchorWindows as StackAnchors gives them. Returns
  // the normalised positions [B, K, 3]. Each sequence starts from a zero
  // regressor state. Throws c10::Error for wrong shapes or missing anchors. An
  // anchored model sets *log_weights (when given) to the log of the
  // hypotheses' weights [B, K, kHypotheses] (-inf: not allowed) and
  // *hypotheses to their positions [B, K, kHypotheses, 3].
  torch::Tensor forward(const torch::Tensor& latents, const torch::Tensor& mask,
                        const struct AnchorBatch* anchors = nullptr,
                        torch::Tensor* log_weights = nullptr, torch::Tensor* hypotheses = nullptr);

  // The fusion of independent windows: [N, M, z], [N, M] -> t^f [N,
  // fused_dim()] (the paper's: MADW, MICA and concatenation, [N, M z]). Late
  // fusion: the masked latents [N, M, z] (its fusion is of positions).
  torch::Tensor Fuse(const torch::Tensor& latents, const torch::Tensor& mask);

  // Online: TE-Align of one window, fusion, one regressor step; returns the
  // position in metres. Windows must come in increasing order of k. A gap of
  // up to kMaxGapWindows windows is stepped through as all-missing windows so
  // the state keeps the window clock; a longer gap restarts from a zero
  // state. Throws std::invalid_argument for k not after the previous window
  // or for bad latents (see TeAlign::Align). No gradient is recorded.
  Eigen::Vector3d Step(const WindowInputs& window);
  // Forgets the recurrent state and the previous window.
  void ResetState();
  static constexpr int kMaxGapWindows = 50;
  // An anchored head's hypotheses: the candidates, the ray's point, a.
  static constexpr int kHypotheses = kAnchorCandidates + 2;

  torch::Tensor NormalizePosition(const torch::Tensor& position_m) const;  // [..., 3]
  torch::Tensor PositionInMetres(const torch::Tensor& normalized) const;   // [..., 3]
  // Throws std::invalid_argument unless centre is finite and scale > 0.
  void SetPositionNormalization(const Eigen::Vector3d& centre_m, double scale_m);

  const UavLocModelConfig& config() const { return config_; }
  const TeAlign& te_align() const { return te_align_; }
  // Anchored models: the anchors the last Step used (default before any).
  const AnchorWindow& last_anchors() const { return last_anchors_; }

  // The paper's fusion (each null when switched off or for a baseline).
  Madw madw{nullptr};
  Mica mica{nullptr};
  // Early fusion's and HeMIS's per-modality projections (else empty).
  torch::nn::ModuleList projections{nullptr};
  // The temporal regressor; null for late fusion, which has one per
  // modality in `branches` and the decision weights' logits `late_logits`
  // [M].
  TemporalRegressor regressor{nullptr};
  torch::nn::ModuleList branches{nullptr};
  torch::Tensor late_logits;

 private:
  torch::Tensor StepAligned(const AlignedWindow& window, const AnchorWindow& anchors);
  void ResetRegressors();  // the temporal state(s) only
  // Late fusion: positions [..., M, 3] of the branches and mask [..., M] ->
  // the weighted position [..., 3] (0 where no modality is available).
  torch::Tensor LateCombine(const torch::Tensor& positions, const torch::Tensor& mask) const;
  // The head's output [..., kHypotheses + 4] (logits, a, t) -> position
  // [..., 3] (anchored models). The candidate hypotheses are the
  // candidates less their offsets (CorrectedCandidates).
  torch::Tensor Anchored(const torch::Tensor& head, const torch::Tensor& candidates,
                         const torch::Tensor& valid, const torch::Tensor& ray,
                         torch::Tensor* log_weights = nullptr,
                         torch::Tensor* hypotheses = nullptr) const;

  // candidates [..., kAnchorCandidates, 3] (normalised) less
  // config.candidate_offset_m.
  torch::Tensor CorrectedCandidates(const torch::Tensor& candidates) const;

  UavLocModelConfig config_;
  TeAlign te_align_;
  AnchorTracker tracker_;
  AnchorWindow last_anchors_;
  TemporalState state_;
  std::vector<TemporalState> branch_states_;  // late fusion
  std::optional<std::int64_t> last_window_;
};
TORCH_MODULE(UavLocModel);

// Aligned windows of B sequences of equal length K as tensors for forward():
// latents [B, K, M, z] and mask [B, K, M] (float32). Throws
// std::invalid_argument if the sequences differ in length or latent size.
struct FusionBatch {
  torch::Tensor latents;
  torch::Tensor mask;
};
FusionBatch StackWindows(const std::vector<std::vector<AlignedWindow>>& sequences);

// AnchorWindows of B sequences of K windows: features [B, K, F], candidates
// [B, K, C, 3], valid [B, K, C] (float32). Throws std::invalid_argument if the
// sequences differ in length or are empty.
struct AnchorBatch {
  torch::Tensor features, candidates, valid;
  torch::Tensor ray;  // [B, K, 7]: AnchorWindow::ray
};
AnchorBatch StackAnchors(const std::vector<std::vector<AnchorWindow>>& sequences);

std::string SidecarPath(const std::string& path);  // path + ".json"
// Throws std::runtime_error naming the file when it cannot be written.
void SaveUavLocModel(const UavLocModel& model, const std::string& path);
UavLocModel LoadUavLocModel(const std::string& path);

}  // namespace uavsim::pipeline
