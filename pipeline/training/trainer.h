// Training UAVLoc in two stages on simulated episodes (paper Sec. VI):
//
//   stage 1  each modality's IB-CC model (feature encoder, mu/sigma MLPs,
//            decoder) on that modality's observations: L = MSE + beta KL
//   stage 2  the edge network (TE-Align, MADW, MICA, Mamba, head) on the
//            sequences of windows of the stage-1 encoders' mu latents that
//            arrived on time, with random modality dropout; L = masked MSE
//
// Adam, early stopping on the validation split, the best weights kept and
// checkpointed, deterministic for a seed and thread count. Torch-free header.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "pipeline/model_bundle.h"
#include "pipeline/node/ib_cc_config.h"
#include "pipeline/training/dataset.h"

namespace uavsim::pipeline {

struct TrainOptions {
  std::uint64_t seed = 1;
  bool quiet = false;  // no progress lines
  int latent_dim = 16;
  double window_s = 0.2;
  double dropout = 0.1;  // paper Sec. VI
  double beta = 1e-3;    // paper Sec. VI
  // The node's compressor: the paper's IB head, or its MLP baseline of equal
  // depth and parameter count (the Sec. VI ablation).
  IbBottleneck bottleneck = IbBottleneck::kIb;
  // Stage 1 (per modality).
  double stage1_lr = 1e-3;
  int stage1_batch = 32;
  int stage1_max_epochs = 30;
  int stage1_patience = 6;
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
  // stage1_label_gate_deg. 0: keep everything (the default: measured worse
  // fused, see NOTES.md).
  double stage1_label_gate_m = 0.0;
  double stage1_label_gate_deg = 0.0;
  // Stage 2.
  double stage2_lr = 1e-3;
  int stage2_batch = 16;
  int stage2_sequence_windows = 60;  // K of a training crop
  int stage2_max_epochs = 150;
  int stage2_patience = 20;
  // Halve the stage-2 learning rate after this many epochs without a better
  // validation loss (0: never; 6 measured better, NOTES.md).
  int stage2_plateau_epochs = 6;
  int stage2_min_steps_per_epoch = 20;
  double modality_dropout = 0.2;  // P(a modality is missing for a whole crop)
  double window_dropout = 0.1;    // P(a modality is missing in one window)
  // Called before every optimisation step; may throw to stop training
  // (the CLI's Ctrl-C). Empty: never stops.
  std::function<void()> check_stop;
  // Edge network sizes (paper silent; DESIGN.md: d_state 16, d_conv 4, expand 2).
  int d_model = 64;
  int layers = 2;
  // The edge head: anchored (default; pipeline/anchored/anchors.h, measured in
  // NOTES.md) or the paper's plain linear head (false).
  bool anchored = true;
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
  // cannot tell, the filtered track is right on average (NOTES.md
  // 2026-11-22 (6); 1 m since the IMM track, (7); 2 m since (8): the head
  // then follows the track where it blended in worse fixes). 0: the nearest.
  double filter_preference_m = 2.0;
  // Anchored head: calibrate each candidate's offset from the target's
  // reference point (the median over the training windows in which it is
  // within this radius of the truth, MedianCandidateOffsets; the model
  // subtracts it, NOTES.md 2026-11-22 (8)). 0: no calibration.
  double offset_calibration_radius_m = 1.0;
  // A candidate valid and within the radius in fewer training windows keeps
  // a zero offset.
  static constexpr std::size_t kMinOffsetWindows = 50;
  // Anchored head: the position loss. true: the expected squared error of
  // the weighted hypotheses, sum_h w_h |c_h - y|^2 (a mixture: weight on a
  // far candidate costs its whole error, so the weights concentrate on the
  // good ones); false: the squared error of the weighted mean |sum_h w_h
  // c_h - y|^2 (a hedge between two far candidates costs little). The
  // validation loss is the weighted mean's in both cases.
  bool mixture_loss = true;

  // Throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

struct StageReport {
  std::string name;                                   // "camera", "lidar", "radar", "fusion"
  std::size_t train_items = 0, validation_items = 0;  // samples or sequences
  std::size_t label_gated_items = 0;  // stage 1: observations left out (not the target)
  int epochs = 0;                     // run before stopping
  int best_epoch = 0;                 // 0: the initial weights
  double initial_validation_loss = 0.0;
  double best_validation_loss = 0.0;
  double seconds = 0.0;
};

// RMSE in metres of the edge network over whole episodes (from window 1, as
// in a run), counting the windows from the first one in which an allowed
// modality arrived. Keys: "all" (every modality that arrived), "camera",
// "lidar", "radar" (only that one; the others masked as missing).
struct Evaluation {
  std::map<std::string, double> rmse_m;
  std::map<std::string, std::size_t> windows;
};

struct TrainReport {
  std::vector<StageReport> stages;
  std::vector<Eigen::Vector3d> candidate_offset_m;  // empty: not calibrated
  Evaluation test;                                  // on the held-out test split
};

// Trains on `data` and writes the model folder `out_dir` (model.json from
// `manifest` with latent_dim and window_s set from the options, the parts,
// training_report.json; checkpoints under out_dir/checkpoints while
// training, removed at the end). Seeds LibTorch's generator with
// options.seed first; call InitTorch() before. A modality with observations
// in training but none in validation is validated on every seventh training
// observation instead. Throws std::invalid_argument for invalid options, an
// empty training or validation split, or episodes whose window_s differs from
// the options', std::runtime_error for I/O.
TrainReport TrainUavLoc(const Dataset& data, const TrainOptions& options,
                        const ModelManifest& manifest, const std::string& out_dir);

// Evaluates a saved model on episodes. Call InitTorch() first.
Evaluation EvaluateModel(const std::string& model_path, const std::vector<Episode>& episodes);

// The report as JSON text (training_report.json).
std::string ReportJson(const TrainReport& report, const TrainOptions& options);

}  // namespace uavsim::pipeline
