// Training UAVLoc in two stages on simulated episodes (paper Sec. VI):
//
//   stage 1  each modality's IB-CC model (feature encoder, mu/sigma MLPs,
//            decoder) on that modality's observations: L = MSE + beta KL
//   stage 2  the edge network (TE-Align, MADW, MICA, Mamba, head) on the
//            sequences of windows of the stage-1 encoders' mu latents that
//            arrived on time, with random modality dropout; L = masked MSE.
//            Once per edge head asked for, on the same encoders: the
//            paper's linear head (method `uavloc`) and our anchored head
//            (`uavloc_anchored`, pipeline/anchored/), each from the
//            generator state stage 1 left, so a head is the same whether
//            trained alone or beside the other.
//
// Adam, early stopping on the validation split, the best weights kept and
// checkpointed, deterministic for a seed and thread count. Torch-free header.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/model_bundle.h"
#include "pipeline/node/ib_cc_config.h"
#include "pipeline/pipeline_config.h"
#include "pipeline/training/dataset.h"
#include "pipeline/training_config.h"

namespace uavsim::pipeline {

// RMSE in metres of a method over whole episodes (from window 1, as in a
// run), counting the windows from the first one in which an allowed modality
// arrived, and only the scored ones (Episode::scored_windows); a method that
// may not answer (the classical ones) counts only the windows it answers.
// Keys, the seven modality subsets (the others masked as missing): "all"
// (camera, LiDAR and radar), "camera+lidar", "camera+radar", "lidar+radar",
// "camera", "lidar", "radar".
struct Evaluation {
  std::map<std::string, double> rmse_m;
  std::map<std::string, std::size_t> windows;
  // Each counted window's squared error (m^2), by key, then by (index of the
  // episode in the list scored, window index k - 1): what OnCommonWindows
  // intersects. Not written to training_report.json.
  std::map<std::string, std::map<std::pair<std::size_t, std::int64_t>, double>> squared_error_m2;
  // The same windows' estimate and true position (world ENU, m), keyed as
  // squared_error_m2: what the downlink's beam is steered at (Fig. 15). Not
  // in training_report.json (test_estimates.csv holds them).
  struct Positions {
    Eigen::Vector3d estimate_m, truth_m;
    int arrived = 0;  // the modalities that arrived in the window (bit m: Modality m)
  };
  std::map<std::string, std::map<std::pair<std::size_t, std::int64_t>, Positions>> position_m;
};

// Each method's scores restricted, per key, to the windows every method of
// `by_method` counted (the same episodes scored by all of them): the "same
// windows" tables. A key with no common window has rmse nan and 0 windows.
std::map<std::string, Evaluation> OnCommonWindows(
    const std::map<std::string, Evaluation>& by_method);

// ModalitySubsetName and kModalitySubsets: pipeline/pipeline_config.h.

// What one training run needs: the tuning knobs (TrainingConfig, data read
// from a config file) and what the caller decides per run.
struct TrainOptions : TrainingConfig {
  std::uint64_t seed = 1;
  bool quiet = false;  // no progress lines
  int latent_dim = 16;
  double window_s = 0.2;
  // The node's compressor: the paper's IB head, or its MLP baseline of equal
  // depth and parameter count (the Sec. VI ablation).
  IbBottleneck bottleneck = IbBottleneck::kIb;
  // The edge heads to train: the paper's linear head and our anchored head
  // (pipeline/anchored/anchors.h, measured in NOTES.md). Neither: stage 1
  // only (the encoders and their decoders' scores, Figs. 7-9).
  bool paper_head = true;
  bool anchored_head = true;
  // The method the paper-layout head is scored as in the report: "uavloc",
  // or a variant's name (VariantMethod, variants.h).
  std::string method = "uavloc";
  // A model folder (or its model.json) whose stage-1 encoders to use instead
  // of training them: stage 2 only, from a generator seeded with `seed`, on
  // the encoders' position normalisation. Their latent size must be
  // latent_dim. Empty: train stage 1.
  std::string encoders_from;
  // Called before every optimisation step and every batch or sequence of
  // the passes between them (validation, encoding, scoring); may throw to
  // stop training (the CLI's Ctrl-C). Empty: never stops.
  std::function<void()> check_stop;
  // Scores methods that need no training (the caller's classical ones: the
  // trainer knows no sensors) on held-out episodes, by method name, under
  // Evaluation's rules; the report puts them beside the heads. Empty: none.
  std::function<std::map<std::string, Evaluation>(const std::vector<Episode>&)> score_classical;

  // Throws std::invalid_argument naming the first bad field: the
  // TrainingConfig rules (training_config.h), then latent_dim (even, >= 2),
  // window_s (> 0), the heads (the anchored head only with the paper's
  // fusion) and method (not empty).
  void Validate() const;
};

struct StageReport {
  // "camera", "lidar", "radar"; "fusion" (the paper's head), "fusion_anchored"
  std::string name;
  std::size_t train_items = 0, validation_items = 0;  // samples or sequences
  std::size_t label_gated_items = 0;  // stage 1: observations left out (not the target)
  int epochs = 0;                     // run before stopping
  int best_epoch = 0;                 // 0: the initial weights
  double initial_validation_loss = 0.0;
  double best_validation_loss = 0.0;
  double seconds = 0.0;
};

// One modality's IB decoder alone on held-out observations, beside the
// information limit of its own input (issue 41). An observation is on
// target when it holds the target: a point within 1 m (LiDAR) or 3 m
// (radar) of the truth at its time stamp, a camera ROI whose left ray
// passes within 1 m of it (ObservationHoldsTarget).
struct DecoderScore {
  double rmse_m = 0.0;  // every observation; nan without observations
  std::size_t observations = 0;
  double on_target_rmse_m = 0.0, off_target_rmse_m = 0.0;  // nan without any
  std::size_t on_target = 0, off_target = 0;
  // The trivial estimator on the same on-target observations: the cloud's
  // centroid; for the camera, the point of the left ray at the true range
  // from the left eye (what the ray alone knows). nan without any.
  double centroid_on_target_m = 0.0;
};

// Whether an observation holds the target (DecoderScore's definition).
bool ObservationHoldsTarget(const Sample& s);
// DecoderScore's trivial estimate for an observation: the cloud's centroid,
// or the camera ray's point at the true range.
Eigen::Vector3d TrivialEstimate(const Sample& s);

// DecoderScore of each modality's encoder-decoder of a saved model (the
// folder or its model.json) on episodes. Call InitTorch() first.
std::map<std::string, DecoderScore> EvaluateDecoders(const std::string& model_path,
                                                     const std::vector<Episode>& episodes);

struct TrainReport {
  DataSplit split = DataSplit::kTrajectory;  // the Dataset's
  std::vector<StageReport> stages;
  std::vector<Eigen::Vector3d> candidate_offset_m;  // empty: not calibrated
  std::string encoders_from;  // TrainOptions::encoders_from (no stage-1 rows then)
  // On the held-out test split, by method name: each head trained
  // ("uavloc", "uavloc_anchored") and the classical methods the caller
  // scored (TrainOptions::score_classical).
  std::map<std::string, Evaluation> test;
  // The same per weather of the test episodes (WeatherOf): method ->
  // weather -> scores; and how many test episodes each weather has.
  std::map<std::string, std::map<std::string, Evaluation>> test_by_weather;
  std::map<std::string, std::size_t> test_weather_episodes;
  // The scored test episodes (Episode::label, WeatherOf), in the order of
  // Evaluation's episode indices: training_report.json's `test_episodes`
  // gives each method's RMSE per episode, over its own windows and over
  // the episode's windows every method counted (where a figure comes from).
  struct TestEpisode {
    int index = -1;  // Episode::index
    std::string label, weather;
  };
  std::vector<TestEpisode> test_episodes;
  // `test` and `test_by_weather` on the windows every method counted
  // (OnCommonWindows, per weather within that weather's episodes).
  std::map<std::string, Evaluation> test_common;
  // Each modality's IB decoder alone on the test episodes (the measure of
  // the paper's Figs. 7-9: no fusion, no alignment): the RMSE (m) of the
  // position it decodes from each observation's mu against the truth at
  // the capture, over the observations of that modality in scored windows
  // (sent on time or not: it is the node's own estimate); by modality name.
  std::map<std::string, DecoderScore> test_decoder;
  // The same on the validation episodes: what stage-1 settings are chosen
  // on (the test episodes' figures are reported, never chosen on).
  std::map<std::string, DecoderScore> validation_decoder;
  // What the nodes sent on the held-out flights, by modality and weather
  // ("all" and WeatherOf's names): observations, and those holding the
  // target (ObservationHoldsTarget).
  struct SentCounts {
    std::size_t sent = 0, holding_target = 0;
  };
  std::map<std::string, std::map<std::string, SentCounts>> test_sent;
  std::map<std::string, std::map<std::string, Evaluation>> test_by_weather_common;
};

// Trains on `data` and writes the model folder `out_dir` (model.json from
// `manifest` with latent_dim, window_s and the training config set from the
// options, the parts,
// training_report.json, test_estimates.csv (`method,subset,episode,window,
// x_m,y_m,z_m,true_x_m,true_y_m,true_z_m`: each head's estimate and the truth
// in every counted test window, by modality subset; episode: index among the
// test episodes with windows; window: k); checkpoints under out_dir/checkpoints while
// training, removed at the end). Seeds LibTorch's generator with
// options.seed first; call InitTorch() before. A modality with observations
// in training but none in validation is validated on every seventh training
// observation instead. Throws std::invalid_argument for invalid options, an
// empty training or validation split, or episodes whose window_s differs from
// the options', std::runtime_error for I/O.
TrainReport TrainUavLoc(const Dataset& data, const TrainOptions& options,
                        const ModelManifest& manifest, const std::string& out_dir);

// Evaluates each edge head of a saved model on episodes, by method name as
// in TrainReport::test. Call InitTorch() first.
std::map<std::string, Evaluation> EvaluateModel(const std::string& model_path,
                                                const std::vector<Episode>& episodes);

// The report as JSON text (training_report.json).
std::string ReportJson(const TrainReport& report, const TrainOptions& options);

}  // namespace uavsim::pipeline
