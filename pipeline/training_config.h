// How UAVLoc is trained (pipeline/training/trainer.h), as data: the tuning
// knobs of both stages and of the anchored head, each with its default. A
// JSON object of these keys (scenarios/training/default.json spells out every
// one; `{}` is valid) is read strictly by Visit: absent keys keep their
// defaults, unknown keys, wrong types and out-of-range values are
// core::ConfigErrors naming the file, the JSON pointer and the rule. The
// resolved config is written into the model's model.json.
//
// What a user chooses per training rather than tunes (seed, the scenario's
// latent size and window, the bottleneck and head variants) is not here but
// in TrainOptions.
#pragma once

#include <cstddef>
#include <string>

#include "core/json_io.h"
#include "pipeline/edge/fusion_kind.h"
#include "pipeline/edge/te_align.h"
#include "pipeline/edge/temporal_kind.h"
#include "pipeline/node/ib_cc_config.h"

namespace uavsim::pipeline {

struct TrainingConfig {
  double dropout = 0.1;  // of the IB-CC models; paper Sec. VI
  double beta = 1e-3;    // paper Sec. VI: IB weight of the KL term
  // The units of the IB-CC loss's L_MSE (IbMseUnits): m^2, the paper's
  // equation with the position in metres, or the scene's normalised units
  // (ours, what models trained before the key used: beta then weighs
  // scale_m^2 more and caps a decoder's precision near
  // sqrt(3 beta / 2) scale_m).
  IbMseUnits ib_mse_units = IbMseUnits::kMetres;
  // Stage 1 (per modality).
  double stage1_lr = 1e-3;  // Adam
  int stage1_batch = 32;
  int stage1_max_epochs = 30;
  int stage1_patience = 6;
  // Halve the stage-1 step after this many epochs without a better
  // validation loss, counted from the last cut (0: never), as stage 2 does.
  int stage1_plateau_epochs = 0;
  int stage1_min_samples_per_epoch = 640;    // small data sets are cycled ...
  int stage1_max_samples_per_epoch = 3000;   // ... large ones sampled
  int stage1_max_validation_samples = 1024;  // evenly spaced over the validation episodes
  // Stage 1 learns where the target is in what a node saw; an observation
  // of something else (a LiDAR or radar cluster of weather returns, a
  // camera ROI on a bird) has no such answer, so its label is noise. Such
  // observations are left out of stage 1 (not of stage 2, which must learn
  // to discount them, nor of any evaluation): a point cluster whose centroid
  // lies farther than stage1_label_gate_m from the truth, a camera ROI whose
  // left bearing is off the truth's direction by more than
  // stage1_label_gate_deg. 0: keep everything (the default; the shipped
  // model's command sets 3 m, docs/methods-and-models.md).
  double stage1_label_gate_m = 0.0;
  double stage1_label_gate_deg = 0.0;
  // Stage 2.
  double stage2_lr = 1e-3;  // Adam
  int stage2_batch = 16;
  int stage2_sequence_windows = 60;  // K of a training crop
  int stage2_max_epochs = 150;
  int stage2_patience = 20;
  // Halve the stage-2 learning rate after this many epochs without a better
  // validation loss (0: never).
  int stage2_plateau_epochs = 6;
  int stage2_min_steps_per_epoch = 20;
  double modality_dropout = 0.2;  // P(a modality is missing for a whole crop)
  double window_dropout = 0.1;    // P(a modality is missing in one window)
  // Edge network sizes (paper silent; DESIGN.md: d_state 16, d_conv 4, expand 2).
  int d_model = 64;
  int layers = 2;
  // The temporal regressor: the paper's Mamba or one of its Sec. VI
  // baselines (GRU, LSTM, TCN), sized to the Mamba's parameter count at
  // d_model and layers (UavLocModelConfig::temporal).
  TemporalKind temporal = TemporalKind::kMamba;
  // MICA's λ^{m,n} at the start (paper Sec. VI: 0.5).
  double mica_lambda_init = 0.5;
  // TE-Align's τ from the window's start (ours) or the episode's clock (the
  // paper's time stamp): TeAlignConfig::tau_origin.
  TauOrigin te_align_tau_origin = TauOrigin::kWindow;
  // The paper's Sec. VI ablations and baselines of the edge network
  // (UavLocModelConfig): TE-Align or a resampling alignment (Fig. 12), MADW
  // and MICA on or off (Fig. 13), the paper's fusion or a fusion baseline
  // (Fig. 14). The variants (variants.h) set them.
  Alignment alignment = Alignment::kTeAlign;
  bool madw = true;
  bool mica = true;
  FusionKind fusion = FusionKind::kUavLoc;
  // The camera's feature encoder (IbCcConfig, pipeline/node/ib_cc_config.h):
  // the paper's two parallel stereo branches or one shared CNN; the average
  // pool of each eye's map (0: none, the paper's); the ROI geometry
  // appended (ours). Their measured effects: NOTES.md.
  StereoBranches camera_stereo_branches = StereoBranches::kShared;
  int camera_eye_pool_side = 4;
  bool camera_roi_geometry = true;
  // The LiDAR's and radar's PointNet (IbCcConfig): points in the scene frame
  // (the paper) or relative to their centroid, the centroid joined to the
  // pooled feature (ours); BatchNorm after each convolution (the paper),
  // GroupNorm of each point's channels, or none (ours).
  PointFrame point_frame = PointFrame::kScene;
  PointNorm point_norm = PointNorm::kBatch;
  // Anchored head: weight of the candidate-selection loss added to the
  // position loss, the cross-entropy of the candidate weights against the
  // valid candidate nearest the truth when it is within selection_radius_m,
  // else the free one (it teaches the choice directly; the MSE alone left
  // the weights spread, NOTES.md). 0: position loss only.
  double selection_weight = 1.0;
  double selection_radius_m = 2.0;
  // The filter's track (pipeline/anchored/anchor_filter.h) is the target whenever it
  // is at most this much farther from the truth than the nearest candidate:
  // which single fix happens to be nearest in a window is luck the features
  // cannot tell, the filtered track is right on average (measured, NOTES.md).
  // 0: the nearest.
  double filter_preference_m = 2.0;
  // Anchored head: calibrate each candidate's offset from the target's
  // reference point (the median over the training windows in which it is
  // within this radius of the truth, MedianCandidateOffsets; the model
  // subtracts it). At most 1 m: the model keeps offsets within 1 m per axis.
  // 0: no calibration.
  double offset_calibration_radius_m = 1.0;
  // A candidate valid and within the radius in fewer training windows keeps
  // a zero offset.
  static constexpr std::size_t kMinOffsetWindows = 50;
  // Anchored head: the position loss ("position_loss" in JSON). true,
  // "mixture": the expected squared error of the weighted hypotheses,
  // sum_h w_h |c_h - y|^2 (weight on a far candidate costs its whole error,
  // so the weights concentrate on the good ones); false, "mean": the squared
  // error of the weighted mean |sum_h w_h c_h - y|^2 (a hedge between two
  // far candidates costs little). The validation loss is the weighted
  // mean's in both cases.
  bool mixture_loss = true;
};

// The keys a model manifest's "training" lacks if it was written before
// they existed read as what such a model was trained with, not as today's
// defaults: ib_mse_units "normalised".
TrainingConfig EarlierModelsTrainingConfig();

// The JSON keys are the field names, except mixture_loss ("position_loss":
// "mixture" | "mean"); camera_stereo_branches is "shared" | "two"; temporal "mamba" | "gru" |
// "lstm" | "tcn"; point_frame "scene" | "centroid"; point_norm "batch" | "group" | "none";
// ib_mse_units "metres" | "normalised";
// alignment "te_align" | "first" | "middle" | "random"; fusion "uavloc" |
// "early" | "late" | "hemis" (a fusion baseline needs madw and mica true). Each rule is checked
// when reading.
template <class V>
void Visit(V& v, TrainingConfig& c);

// `defaults` filled from the object `doc` (strictly, see above); `file` names
// it in messages. Throws core::ConfigError.
TrainingConfig TrainingConfigFromJson(const core::Json& doc, const std::string& file,
                                      TrainingConfig defaults = {});

// Every key of `c`, defaults filled, in Visit's order.
core::Json TrainingConfigJson(const TrainingConfig& c);

// Checks `c` against the rules Visit applies when reading; throws
// core::ConfigError naming `file` and the first bad key's pointer.
void CheckTrainingConfig(const TrainingConfig& c, const std::string& file);

}  // namespace uavsim::pipeline
