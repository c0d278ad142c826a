#include "pipeline/training/trainer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "core/json_io.h"
#include "core/physical_constants.h"
#include "core/progress.h"
#include "pipeline/edge/te_align.h"
#include "pipeline/edge/uavloc_model.h"
#include "pipeline/model_checksums.h"
#include "pipeline/node/ib_encoder.h"
#include "pipeline/node/ib_model_io.h"
#include "pipeline/node/ib_normalization.h"
#include "pipeline/variants.h"

namespace uavsim::pipeline {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* const kPartNames[kModalityCount] = {"camera", "lidar", "radar"};

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The best weights seen so far, kept in memory (parameters and buffers, in
// the module's deterministic order).
class BestWeights {
 public:
  void Take(const torch::nn::Module& m) {
    torch::NoGradGuard no_grad;
    saved_.clear();
    for (const auto& p : m.parameters()) saved_.push_back(p.detach().clone());
    for (const auto& b : m.buffers()) saved_.push_back(b.detach().clone());
  }
  void Restore(torch::nn::Module& m) const {
    torch::NoGradGuard no_grad;
    std::size_t i = 0;
    for (auto& p : m.parameters()) p.copy_(saved_.at(i++));
    for (auto& b : m.buffers()) b.copy_(saved_.at(i++));
  }

 private:
  std::vector<torch::Tensor> saved_;
};

// Early stopping on a validation loss: remembers the best epoch and says when
// `patience` epochs have passed without improvement.
struct EarlyStopping {
  int patience;
  double best = std::numeric_limits<double>::infinity();
  int best_epoch = 0, since_best = 0;
  // True if `loss` is the new best.
  bool Add(int epoch, double loss) {
    if (loss < best) {
      best = loss, best_epoch = epoch, since_best = 0;
      return true;
    }
    ++since_best;
    return false;
  }
  bool Stop() const { return since_best >= patience; }
};

// The temporal regressor as progress lines name it.
std::string RegressorLabel(TemporalKind kind) {
  switch (kind) {
    case TemporalKind::kMamba:
      return "Mamba";
    case TemporalKind::kGru:
      return "GRU";
    case TemporalKind::kLstm:
      return "LSTM";
    case TemporalKind::kTcn:
      return "TCN";
  }
  return TemporalKindName(kind);
}

// The epochs of one stage: train an epoch, validate, keep (and checkpoint)
// the best weights, stop when `patience` epochs bring no improvement; ends
// with the best weights restored, in eval mode. Fills the report's epoch
// fields; report.initial_validation_loss must be set.
template <class TrainEpoch, class Validate, class Checkpoint>
void RunEpochs(torch::nn::Module& model, int max_epochs, int patience, const std::string& label,
               bool quiet, TrainEpoch train_epoch, Validate validate, Checkpoint checkpoint,
               StageReport& report, std::function<void(int)> epochs_since_best = {}) {
  BestWeights best;
  best.Take(model);
  EarlyStopping stopping{patience};
  stopping.Add(0, report.initial_validation_loss);
  core::Progress progress(label, max_epochs, "epochs", quiet);
  int epoch = 1;
  for (; epoch <= max_epochs; ++epoch) {
    model.train();
    train_epoch();
    if (stopping.Add(epoch, validate())) {
      best.Take(model);
      checkpoint(epoch);
    }
    progress.Update(epoch);
    if (stopping.Stop()) break;
    if (epochs_since_best) epochs_since_best(epoch - stopping.best_epoch);
  }
  progress.Finish();
  best.Restore(model);
  model.eval();
  report.epochs = std::min(epoch, max_epochs);
  report.best_epoch = stopping.best_epoch;
  report.best_validation_loss = stopping.best;
}

// RunEpochs' epochs_since_best: halves Adam's step after `plateau_epochs`
// epochs without a better validation loss, counted from the last cut (0: never).
std::function<void(int)> HalveOnPlateau(torch::optim::Adam& adam, double lr, int plateau_epochs) {
  return [&adam, lr, plateau_epochs, since_cut = 0](int since_best) mutable {
    if (plateau_epochs <= 0 || std::min(since_best, ++since_cut) < plateau_epochs) return;
    lr *= 0.5;
    since_cut = 0;
    for (auto& group : adam.param_groups())
      static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
  };
}

// ---- What an observation holds (DecoderScore) ----

constexpr double kLidarHoldsTargetM = 1.0, kRadarHoldsTargetM = 3.0, kCameraHoldsTargetM = 1.0;

Eigen::Vector3d PointAt(const PointObservation& p, std::size_t i) {
  const float* v = &p.values[i * static_cast<std::size_t>(p.channels)];
  return {v[0], v[1], v[2]};
}

// ---- Stage 1: one modality's IB-CC model on its observations ----

// The samples of modality m captured in the episodes' scored windows
// (Episode::scored_windows; `align` places them).
std::vector<const Sample*> SamplesOf(const std::vector<Episode>& episodes, Modality m,
                                     const TeAlign& align) {
  std::vector<const Sample*> out;
  for (const Episode& e : episodes)
    for (const Sample& s : e.samples)
      if (s.modality == m && (e.scored_windows.empty() || e.Scored(align.WindowOf(s.t_s))))
        out.push_back(&s);
  return out;
}

// Whether an observation shows the target (TrainOptions::stage1_label_gate_*).
bool ShowsTarget(const Sample& s, const TrainOptions& o) {
  if (s.camera) {
    if (!(o.stage1_label_gate_deg > 0)) return true;
    const Eigen::Vector3d to_truth = (s.truth_m - s.camera->eye_left_w).normalized();
    const double cos_angle =
        std::clamp(to_truth.dot(s.camera->bearing_left_w.normalized()), -1.0, 1.0);
    return std::acos(cos_angle) <= o.stage1_label_gate_deg * core::kPi / 180.0;
  }
  if (!s.points || !(o.stage1_label_gate_m > 0)) return true;
  const PointObservation& p = *s.points;
  if (p.count() == 0) return false;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p.count(); ++i)
    centroid += Eigen::Vector3d(p.values[i * p.channels], p.values[i * p.channels + 1],
                                p.values[i * p.channels + 2]);
  centroid /= static_cast<double>(p.count());
  return (centroid - s.truth_m).norm() <= o.stage1_label_gate_m;
}

std::vector<const Sample*> TargetSamplesOf(const std::vector<Episode>& episodes, Modality m,
                                           const TrainOptions& o, std::size_t* dropped) {
  std::vector<const Sample*> out;
  TeAlignConfig windows;
  windows.latent_dim = o.latent_dim;
  windows.window_s = o.window_s;
  for (const Sample* s : SamplesOf(episodes, m, TeAlign(windows)))
    ShowsTarget(*s, o) ? out.push_back(s) : void(++*dropped);
  return out;
}

// At most `n` of `all`, evenly spaced (every episode and time represented).
std::vector<const Sample*> EvenSubset(const std::vector<const Sample*>& all, int n) {
  if (static_cast<int>(all.size()) <= n) return all;
  std::vector<const Sample*> out;
  for (int i = 0; i < n; ++i) out.push_back(all[all.size() * static_cast<std::size_t>(i) / n]);
  return out;
}

IbInput MakeInput(const std::vector<const Sample*>& batch, Modality m, const IbNormalization& n) {
  if (m == Modality::kCamera) {
    std::vector<const CameraObservation*> obs;
    for (const Sample* s : batch) obs.push_back(&*s->camera);
    return MakeCameraInput(obs, n);
  }
  std::vector<const PointObservation*> obs;
  for (const Sample* s : batch) obs.push_back(&*s->points);
  return MakePointInput(obs, m, n);
}

// TrainOptions::check_stop of the TrainUavLoc call under way on this
// thread, polled by the long loops between optimisation steps too
// (validation passes, encoding, scoring: on raw data each can run for
// minutes), so a termination signal is honoured promptly (issue 24).
thread_local const std::function<void()>* g_check_stop = nullptr;

void PollStop() {
  if (g_check_stop && *g_check_stop) (*g_check_stop)();
}

struct StopScope {
  explicit StopScope(const std::function<void()>& f) { g_check_stop = &f; }
  ~StopScope() { g_check_stop = nullptr; }
  StopScope(const StopScope&) = delete;
  StopScope& operator=(const StopScope&) = delete;
};

torch::Tensor MakeTarget(const std::vector<const Sample*>& batch, const IbNormalization& n) {
  std::vector<Eigen::Vector3d> truth;
  for (const Sample* s : batch) truth.push_back(s->truth_m);
  return MakePositionTarget(truth, n);
}

// Mean validation loss (eval mode: t = mu, no dropout), weighted by batch size.
double IbValidationLoss(IbCcModel& model, const std::vector<const Sample*>& samples, int batch) {
  if (samples.empty()) return 0.0;
  torch::NoGradGuard no_grad;
  model->eval();
  const IbNormalization& n = model->config().normalization;
  double sum = 0.0;
  for (std::size_t i = 0; i < samples.size(); i += static_cast<std::size_t>(batch)) {
    PollStop();
    const std::vector<const Sample*> b(
        samples.begin() + static_cast<std::ptrdiff_t>(i),
        samples.begin() + static_cast<std::ptrdiff_t>(
                              std::min(samples.size(), i + static_cast<std::size_t>(batch))));
    const IbOutput out = model->forward(MakeInput(b, model->config().modality, n));
    sum += model->Loss(out, MakeTarget(b, n)).total.item<double>() * static_cast<double>(b.size());
  }
  return sum / static_cast<double>(samples.size());
}

IbCcModel TrainEncoder(Modality m, const Dataset& data, const TrainOptions& o,
                       const IbNormalization& norm, const std::string& checkpoint,
                       StageReport& report) {
  const auto start = Clock::now();
  IbCcConfig config;
  config.modality = m;
  config.latent_dim = o.latent_dim;
  config.dropout = o.dropout;
  config.beta = o.beta;
  config.mse_units = o.ib_mse_units;
  config.bottleneck = o.bottleneck;
  config.normalization = norm;
  config.stereo_branches = o.camera_stereo_branches;
  config.eye_pool_side = o.camera_eye_pool_side;
  config.roi_geometry = o.camera_roi_geometry;
  config.point_frame = o.point_frame;
  config.point_norm = o.point_norm;
  IbCcModel model(config);
  std::size_t dropped = 0;
  std::vector<const Sample*> train = TargetSamplesOf(data.train, m, o, &dropped);
  std::vector<const Sample*> val = TargetSamplesOf(data.validation, m, o, &dropped);
  report.label_gated_items = dropped;
  if (val.empty() && train.size() >= 14) {
    // The validation trajectories never saw this modality: hold back every
    // seventh training observation instead.
    std::vector<const Sample*> kept;
    for (std::size_t i = 0; i < train.size(); ++i) (i % 7 == 6 ? val : kept).push_back(train[i]);
    train = std::move(kept);
  }
  // Early stopping on the validation observations that hold the target
  // (issue 41): an observation of clutter has no position to learn, and its
  // noise label would flatten the curve. All of them if none does.
  std::vector<const Sample*> val_on_target;
  for (const Sample* s : val)
    if (ObservationHoldsTarget(*s)) val_on_target.push_back(s);
  if (!val_on_target.empty()) val = std::move(val_on_target);
  val = EvenSubset(val, o.stage1_max_validation_samples);
  report.name = kPartNames[static_cast<int>(m)];
  report.train_items = train.size();
  report.validation_items = val.size();
  report.initial_validation_loss = IbValidationLoss(model, val, o.stage1_batch);
  report.best_validation_loss = report.initial_validation_loss;
  // A modality the training episodes never observed keeps its initial weights.
  if (train.size() < 2 || val.empty()) {
    model->eval();
    report.seconds = SecondsSince(start);
    return model;
  }

  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(o.stage1_lr));
  const auto n = static_cast<std::int64_t>(train.size());
  const std::int64_t per_epoch =
      std::clamp<std::int64_t>(n, o.stage1_min_samples_per_epoch, o.stage1_max_samples_per_epoch);
  RunEpochs(
      *model, o.stage1_max_epochs, o.stage1_patience, "train stage 1: " + report.name, o.quiet,
      [&] {
        // Shuffled passes over the training set, as many as fill the epoch.
        std::vector<torch::Tensor> passes;
        for (std::int64_t drawn = 0; drawn < per_epoch; drawn += n)
          passes.push_back(torch::randperm(n, torch::TensorOptions().dtype(torch::kLong)));
        const torch::Tensor order = torch::cat(passes);
        const auto* idx = order.data_ptr<std::int64_t>();
        for (std::int64_t i = 0; i + 1 < per_epoch; i += o.stage1_batch) {
          std::vector<const Sample*> batch;
          for (std::int64_t j = i; j < std::min<std::int64_t>(per_epoch, i + o.stage1_batch); ++j)
            batch.push_back(train[static_cast<std::size_t>(idx[j])]);
          if (batch.size() < 2) break;  // BatchNorm needs two
          if (o.check_stop) o.check_stop();
          adam.zero_grad();
          const IbOutput out = model->forward(MakeInput(batch, m, norm));
          model->Loss(out, MakeTarget(batch, norm)).total.backward();
          adam.step();
        }
      },
      [&] { return IbValidationLoss(model, val, o.stage1_batch); },
      [&](int epoch) {
        SaveIbCcModel(model, checkpoint, "checkpoint: epoch " + std::to_string(epoch));
      },
      report, HalveOnPlateau(adam, o.stage1_lr, o.stage1_plateau_epochs));
  report.seconds = SecondsSince(start);
  return model;
}

// ---- Stage 2: the edge network on sequences of aligned windows ----

// One episode as the edge saw it: per window the aligned latents and masks,
// and the truth (normalised).
struct WindowSequence {
  torch::Tensor latents;  // [K, M, z]
  torch::Tensor mask;     // [K, M]
  torch::Tensor truth;    // [K, 3]
  torch::Tensor scored;   // [K]: 1 for the windows whose truth this part uses
  // Per window, each modality's anchors (pipeline/anchored/anchors.h).
  std::vector<WindowAnchors> anchors;
};

// mu of every sample, in the episodes' order.
std::vector<std::vector<std::vector<float>>> EncodeEpisodes(const std::vector<Episode>& episodes,
                                                            std::vector<IbCcModel>& encoders) {
  torch::NoGradGuard no_grad;
  std::vector<std::vector<std::vector<float>>> latents(episodes.size());
  for (std::size_t e = 0; e < episodes.size(); ++e) {
    const SampleList& samples = episodes[e].samples;
    latents[e].resize(samples.size());
    for (int m = 0; m < kModalityCount; ++m) {
      IbCcModel& model = encoders[static_cast<std::size_t>(m)];
      model->eval();
      std::vector<std::size_t> index;
      for (std::size_t i = 0; i < samples.size(); ++i)
        if (static_cast<int>(samples[i].modality) == m) index.push_back(i);
      for (std::size_t i = 0; i < index.size(); i += 64) {
        PollStop();
        std::vector<const Sample*> batch;
        for (std::size_t j = i; j < std::min(index.size(), i + 64); ++j)
          batch.push_back(&samples[index[j]]);
        const torch::Tensor mu =
            model->Encode(MakeInput(batch, static_cast<Modality>(m), model->config().normalization))
                .contiguous();
        const float* p = mu.data_ptr<float>();
        const auto z = static_cast<std::size_t>(mu.size(1));
        for (std::size_t j = 0; j < batch.size(); ++j)
          latents[e][index[i + j]].assign(p + j * z, p + (j + 1) * z);
      }
    }
  }
  return latents;
}

// TE-Align of each window of an episode from the on-time samples' latents.
WindowSequence AlignEpisode(const Episode& ep, const std::vector<std::vector<float>>& latents,
                            const TeAlign& align, const IbNormalization& norm) {
  const auto k_count = static_cast<std::int64_t>(ep.window_truth.size());
  std::vector<WindowInputs> inputs(static_cast<std::size_t>(k_count));
  for (std::int64_t k = 0; k < k_count; ++k) inputs[static_cast<std::size_t>(k)].window = k + 1;
  for (std::size_t i = 0; i < ep.samples.size(); ++i) {
    const Sample& s = ep.samples[i];
    if (!s.on_time) continue;
    const std::int64_t k = align.WindowOf(s.t_s);
    if (k < 1 || k > k_count) continue;
    inputs[static_cast<std::size_t>(k - 1)].frames[static_cast<int>(s.modality)].push_back(
        {s.t_s, latents[i], s.camera ? AnchorOf(*s.camera) : AnchorOf(*s.points)});
  }
  std::vector<std::vector<AlignedWindow>> one(1);
  WindowSequence seq;
  for (const WindowInputs& w : inputs) {
    one[0].push_back(align.Align(w));
    seq.anchors.push_back(align.AnchorsOf(w));
  }
  const FusionBatch b = StackWindows(one);
  seq.latents = b.latents[0];
  seq.mask = b.mask[0];
  std::vector<Eigen::Vector3d> truth(ep.window_truth.begin(), ep.window_truth.end());
  seq.truth = MakePositionTarget(truth, norm);
  seq.scored = torch::ones({k_count});
  for (std::int64_t k = 1; k <= k_count; ++k)
    if (!ep.Scored(k)) seq.scored[k - 1] = 0.0;
  return seq;
}

// 1 from the first window in which any modality is available, else 0: the
// windows a run reports an estimate for. mask [B, K, M] -> [B, K].
torch::Tensor EstimatedWindows(const torch::Tensor& mask) {
  return (std::get<0>(mask.amax(2).cummax(1)) > 0.5).to(torch::kFloat32);
}

// The windows a loss or a score counts, [B, K]: estimated (mask [B, K, M])
// and scored in this part (scored [B, K]).
torch::Tensor CountedWindows(const torch::Tensor& mask, const torch::Tensor& scored) {
  return EstimatedWindows(mask) * scored;
}

// Mean squared error (summed over x, y, z) over the counted windows w [B, K].
torch::Tensor MaskedMse(const torch::Tensor& y_hat, const torch::Tensor& y,
                        const torch::Tensor& w) {
  return ((y_hat - y).square().sum(2) * w).sum() / w.sum().clamp_min(1.0);
}

// The anchors the edge would hold over windows [start, start + K) of `s` from
// a fresh tracker, where mask [K, M] is what arrived: a modality masked out in
// a window brings no anchor either.
std::vector<AnchorWindow> TrackAnchors(const WindowSequence& s, std::int64_t start,
                                       const torch::Tensor& mask, const UavLocModelConfig& c) {
  AnchorTracker tracker(c.window_s, c.position_centre_m, c.position_scale_m);
  const torch::Tensor m = mask.to(torch::kFloat32).contiguous();
  const auto acc = m.accessor<float, 2>();
  std::vector<AnchorWindow> out;
  for (std::int64_t i = 0; i < m.size(0); ++i) {
    WindowAnchors arrived = s.anchors[static_cast<std::size_t>(start + i)];
    for (int j = 0; j < kModalityCount; ++j)
      if (acc[i][j] < 0.5f) arrived[static_cast<std::size_t>(j)].clear();
    out.push_back(tracker.Update(i + 1, arrived));
  }
  return out;
}

// The whole sequence through the model with what mask [K, M] lets arrive:
// normalised positions [1, K, 3].
torch::Tensor ForwardSequence(UavLocModel& model, const WindowSequence& s,
                              const torch::Tensor& mask) {
  const torch::Tensor latents = (s.latents * mask.unsqueeze(2)).unsqueeze(0);
  if (!model->config().anchored) return model->forward(latents, mask.unsqueeze(0));
  const AnchorBatch anchors = StackAnchors({TrackAnchors(s, 0, mask, model->config())});
  return model->forward(latents, mask.unsqueeze(0), &anchors);
}

// The candidates' offsets from the truth over the training sequences as
// the edge's tracker would give them (MedianCandidateOffsets).
std::vector<Eigen::Vector3d> CandidateOffsets(const std::vector<WindowSequence>& train,
                                              const UavLocModelConfig& c, double radius_m) {
  std::vector<AnchorWindow> windows;
  std::vector<Eigen::Vector3d> truth;
  for (const WindowSequence& s : train) {
    const std::vector<AnchorWindow> a = TrackAnchors(s, 0, s.mask, c);
    const torch::Tensor y = s.truth.to(torch::kFloat64).contiguous();
    const auto acc = y.accessor<double, 2>();
    const auto scored = s.scored.accessor<float, 1>();
    for (std::int64_t k = 0; k < y.size(0); ++k) {
      if (scored[k] < 0.5f) continue;  // another part's label
      windows.push_back(a[static_cast<std::size_t>(k)]);
      truth.emplace_back(acc[k][0], acc[k][1], acc[k][2]);
    }
  }
  const auto offsets = MedianCandidateOffsets(windows, truth, c.position_scale_m, radius_m,
                                              TrainOptions::kMinOffsetWindows);
  return {offsets.begin(), offsets.end()};
}

// Cross-entropy of the anchored head's weights log_w [B, K, H] over its
// hypotheses h [B, K, H, 3] against the valid candidate nearest the truth
// [B, K, 3] (the filter's track preferred by `preference`, normalised) if
// within `radius` (normalised), else the nearer of the two free hypotheses;
// mean over the counted windows w [B, K].
torch::Tensor SelectionLoss(const torch::Tensor& log_w, const torch::Tensor& h,
                            const torch::Tensor& truth, const torch::Tensor& w, double radius,
                            double preference) {
  const torch::Tensor d =
      (h.detach() - truth.unsqueeze(-2))
          .norm(2, -1)
          .masked_fill(~torch::isfinite(log_w.detach()), std::numeric_limits<float>::infinity());
  torch::Tensor bonus = torch::zeros({kAnchorCandidates});
  bonus[kFilterCandidate] = preference;
  const auto [nearest, index] = (d.narrow(-1, 0, kAnchorCandidates) - bonus).min(-1);
  const torch::Tensor free = d.narrow(-1, kAnchorCandidates, 2).argmin(-1) + kAnchorCandidates;
  const torch::Tensor target = torch::where(nearest < radius, index, free);
  return -(log_w.gather(-1, target.unsqueeze(-1)).squeeze(-1) * w).sum() / w.sum().clamp_min(1.0);
}

// The expected squared error of the anchored head's hypotheses h [B, K, H,
// 3] under their weights exp(log_w) [B, K, H] against the truth [B, K, 3],
// over the counted windows w [B, K].
torch::Tensor MixtureMse(const torch::Tensor& log_w, const torch::Tensor& h,
                         const torch::Tensor& truth, const torch::Tensor& w) {
  const torch::Tensor expected = (log_w.exp() * (h - truth.unsqueeze(-2)).square().sum(-1)).sum(-1);
  return (expected * w).sum() / w.sum().clamp_min(1.0);
}

double FusionValidationLoss(UavLocModel& model, const std::vector<WindowSequence>& val) {
  torch::NoGradGuard no_grad;
  model->eval();
  double sum = 0.0, count = 0.0;
  for (const WindowSequence& s : val) {
    PollStop();
    const torch::Tensor mask = s.mask.unsqueeze(0);
    const torch::Tensor y_hat = ForwardSequence(model, s, s.mask);
    const torch::Tensor w = CountedWindows(mask, s.scored.unsqueeze(0));
    sum += ((y_hat - s.truth.unsqueeze(0)).square().sum(2) * w).sum().item<double>();
    count += w.sum().item<double>();
  }
  return count > 0 ? sum / count : 0.0;
}

// A training batch: random crops of K windows from random episodes, with
// random modality dropout (a modality missing for the whole crop, or in
// single windows), never more than the data already lacks.
struct CropBatch {
  FusionBatch fusion;
  AnchorBatch anchors;
  torch::Tensor truth;
  torch::Tensor scored;  // [B, K]
};
CropBatch DrawCrops(const std::vector<WindowSequence>& train, int batch, std::int64_t k,
                    const TrainOptions& o, const UavLocModelConfig& config) {
  std::vector<torch::Tensor> lat, mask, y, scored;
  std::vector<std::vector<AnchorWindow>> anchors;
  const torch::Tensor pick =
      torch::randint(static_cast<std::int64_t>(train.size()), {batch}, torch::kLong);
  for (int b = 0; b < batch; ++b) {
    const WindowSequence& s = train[static_cast<std::size_t>(pick[b].item<std::int64_t>())];
    const std::int64_t windows = s.latents.size(0);
    // Half the crops start at the first window, as a run does.
    std::int64_t start = 0;
    if (windows > k && torch::rand({1}).item<double>() >= 0.5)
      start = torch::randint(windows - k + 1, {1}, torch::kLong).item<std::int64_t>();
    torch::Tensor m = s.mask.narrow(0, start, k).clone();
    torch::Tensor keep = (torch::rand({1, kModalityCount}) >= o.modality_dropout).to(m.dtype());
    if (keep.sum().item<double>() < 0.5) keep.fill_(1.0);  // never drop all three
    m = m * keep * (torch::rand({k, kModalityCount}) >= o.window_dropout).to(m.dtype());
    lat.push_back(s.latents.narrow(0, start, k) * m.unsqueeze(2));
    if (config.anchored) anchors.push_back(TrackAnchors(s, start, m, config));
    mask.push_back(m);
    y.push_back(s.truth.narrow(0, start, k));
    scored.push_back(s.scored.narrow(0, start, k));
  }
  return {{torch::stack(lat), torch::stack(mask)},
          config.anchored ? StackAnchors(anchors) : AnchorBatch{},
          torch::stack(y),
          torch::stack(scored)};
}

UavLocModel TrainFusion(const std::vector<WindowSequence>& train,
                        const std::vector<WindowSequence>& val, const UavLocModelConfig& config,
                        const TrainOptions& o, const std::string& checkpoint, StageReport& report) {
  const auto start = Clock::now();
  UavLocModel model(config);
  report.name = config.anchored ? "fusion_anchored" : "fusion";
  report.train_items = train.size();
  report.validation_items = val.size();
  report.initial_validation_loss = FusionValidationLoss(model, val);
  std::int64_t k = o.stage2_sequence_windows;
  for (const WindowSequence& s : train) k = std::min<std::int64_t>(k, s.latents.size(0));

  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(o.stage2_lr));
  // An epoch sees about every training window twice.
  std::int64_t windows = 0;
  for (const WindowSequence& s : train) windows += s.latents.size(0);
  const std::int64_t steps = std::max<std::int64_t>(
      o.stage2_min_steps_per_epoch, 2 * windows / (k * static_cast<std::int64_t>(o.stage2_batch)));
  RunEpochs(
      *model, o.stage2_max_epochs, o.stage2_patience,
      "train stage 2: " +
          (config.fusion == FusionKind::kUavLoc
               ? std::string("fusion")
               : FusionKindName(config.fusion) + std::string(" fusion")) +
          " + " + RegressorLabel(config.temporal) +
          (config.anchored ? ", anchored head" : ", " + o.method),
      o.quiet,
      [&] {
        for (std::int64_t step = 0; step < steps; ++step) {
          const CropBatch b = DrawCrops(train, o.stage2_batch, k, o, config);
          if (o.check_stop) o.check_stop();
          adam.zero_grad();
          torch::Tensor log_w, hypotheses;
          const torch::Tensor y_hat =
              model->forward(b.fusion.latents, b.fusion.mask,
                             config.anchored ? &b.anchors : nullptr, &log_w, &hypotheses);
          const torch::Tensor w = CountedWindows(b.fusion.mask, b.scored);
          torch::Tensor loss = config.anchored && o.mixture_loss
                                   ? MixtureMse(log_w, hypotheses, b.truth, w)
                                   : MaskedMse(y_hat, b.truth, w);
          if (config.anchored && o.selection_weight > 0.0)
            loss = loss + o.selection_weight *
                              SelectionLoss(log_w, hypotheses, b.truth, w,
                                            o.selection_radius_m / config.position_scale_m,
                                            o.filter_preference_m / config.position_scale_m);
          loss.backward();
          adam.step();
        }
      },
      [&] { return FusionValidationLoss(model, val); },
      [&](int) { SaveUavLocModel(model, checkpoint); }, report,
      HalveOnPlateau(adam, o.stage2_lr, o.stage2_plateau_epochs));
  report.seconds = SecondsSince(start);
  return model;
}

Evaluation Evaluate(UavLocModel& model, const std::vector<WindowSequence>& sequences) {
  torch::NoGradGuard no_grad;
  model->eval();
  Evaluation ev;
  const double scale = model->config().position_scale_m;
  const Eigen::Vector3d centre = model->config().position_centre_m;
  // Head output (p - centre) / scale -> p, world ENU metres.
  const auto world = [&](const torch::Tensor& row) {
    const torch::Tensor r = row.to(torch::kDouble).contiguous();
    const double* v = r.data_ptr<double>();
    return Eigen::Vector3d(centre + scale * Eigen::Vector3d(v[0], v[1], v[2]));
  };
  for (int bits = 1; bits <= kModalitySubsets; ++bits) {
    const std::string key = ModalitySubsetName(bits);
    double sum = 0.0, count = 0.0;
    for (const WindowSequence& s : sequences) {
      PollStop();
      torch::Tensor keep = torch::zeros({1, kModalityCount});
      for (int m = 0; m < kModalityCount; ++m)
        if (bits & (1 << m)) keep[0][m] = 1.0;
      const torch::Tensor mask = (s.mask * keep).unsqueeze(0);
      const torch::Tensor y_hat = ForwardSequence(model, s, mask[0]);
      const torch::Tensor w = CountedWindows(mask, s.scored.unsqueeze(0));
      const torch::Tensor squared = ((y_hat - s.truth.unsqueeze(0)).square().sum(2) * w)[0];
      sum += squared.sum().item<double>();
      count += w.sum().item<double>();
      const torch::Tensor counted = w[0].contiguous(), errors = squared.contiguous();
      const torch::Tensor present = (mask[0] > 0.5).to(torch::kInt32).contiguous();
      const auto c = counted.accessor<float, 1>();
      const auto e = errors.accessor<float, 1>();
      const auto a = present.accessor<int, 2>();
      auto& windows = ev.squared_error_m2[key];
      auto& positions = ev.position_m[key];
      const std::size_t episode = static_cast<std::size_t>(&s - sequences.data());
      for (std::int64_t j = 0; j < c.size(0); ++j)
        if (c[j] > 0.0f) {
          windows[{episode, j}] = scale * scale * static_cast<double>(e[j]);
          int arrived = 0;
          for (int m = 0; m < kModalityCount; ++m) arrived |= a[j][m] << m;
          positions[{episode, j}] = {world(y_hat[0][j]), world(s.truth[j]), arrived};
        }
    }
    ev.windows[key] = static_cast<std::size_t>(count);
    ev.rmse_m[key] =
        count > 0 ? scale * std::sqrt(sum / count) : std::numeric_limits<double>::quiet_NaN();
  }
  return ev;
}

std::vector<WindowSequence> AlignAll(const std::vector<Episode>& episodes,
                                     std::vector<IbCcModel>& encoders, const TeAlign& align,
                                     const IbNormalization& norm) {
  const auto latents = EncodeEpisodes(episodes, encoders);
  std::vector<WindowSequence> out;
  for (std::size_t e = 0; e < episodes.size(); ++e)
    if (!episodes[e].window_truth.empty())
      out.push_back(AlignEpisode(episodes[e], latents[e], align, norm));
  return out;
}

// TrainReport::test_decoder of the encoders on episodes.
std::map<std::string, DecoderScore> DecoderScores(std::vector<IbCcModel>& encoders,
                                                  const std::vector<Episode>& episodes,
                                                  const TeAlign& align) {
  torch::NoGradGuard no_grad;
  std::map<std::string, DecoderScore> out;
  const auto rmse = [](double sum, std::size_t n) {
    return n == 0 ? std::numeric_limits<double>::quiet_NaN()
                  : std::sqrt(sum / static_cast<double>(n));
  };
  for (int m = 0; m < kModalityCount; ++m) {
    IbCcModel& model = encoders[static_cast<std::size_t>(m)];
    model->eval();
    const IbNormalization& n = model->config().normalization;
    const std::vector<const Sample*> samples = SamplesOf(episodes, static_cast<Modality>(m), align);
    double sum = 0.0, sum_on = 0.0, sum_off = 0.0, sum_trivial = 0.0;
    DecoderScore& d = out[kPartNames[m]];
    for (std::size_t i = 0; i < samples.size(); i += 64) {
      PollStop();
      const std::vector<const Sample*> b(
          samples.begin() + static_cast<std::ptrdiff_t>(i),
          samples.begin() + static_cast<std::ptrdiff_t>(std::min(samples.size(), i + 64)));
      const torch::Tensor y =
          model->Decode(model->Encode(MakeInput(b, static_cast<Modality>(m), n)))
              .to(torch::kFloat64)
              .contiguous();
      const double* p = y.data_ptr<double>();
      for (std::size_t j = 0; j < b.size(); ++j) {
        const double e2 =
            (DenormalizePosition({p[3 * j], p[3 * j + 1], p[3 * j + 2]}, n) - b[j]->truth_m)
                .squaredNorm();
        sum += e2;
        if (ObservationHoldsTarget(*b[j])) {
          sum_on += e2, ++d.on_target;
          sum_trivial += (TrivialEstimate(*b[j]) - b[j]->truth_m).squaredNorm();
        } else {
          sum_off += e2, ++d.off_target;
        }
      }
    }
    d.observations = samples.size();
    d.rmse_m = rmse(sum, samples.size());
    d.on_target_rmse_m = rmse(sum_on, d.on_target);
    d.off_target_rmse_m = rmse(sum_off, d.off_target);
    d.centroid_on_target_m = rmse(sum_trivial, d.on_target);
  }
  return out;
}

// The stage-1 encoders of a saved model (TrainOptions::encoders_from).
// The camera, LiDAR and radar encoders of the model whose manifest is
// `manifest_path`.
std::vector<IbCcModel> ManifestEncoders(const ModelManifest& m, const std::string& manifest_path) {
  const fs::path folder = fs::path(manifest_path).parent_path();
  std::vector<IbCcModel> encoders;
  for (const std::string* name : {&m.camera, &m.lidar, &m.radar})
    encoders.push_back(LoadIbCcModel((folder / *name).string()));
  return encoders;
}

std::vector<IbCcModel> LoadEncoders(const std::string& model_path, int latent_dim,
                                    std::optional<TrainingConfig>* trained_with) {
  const std::string manifest_path = ModelManifestPath(model_path);
  const ModelManifest m = ReadModelManifest(manifest_path);
  VerifyModelChecksums(fs::path(manifest_path).parent_path().string());
  if (m.latent_dim != latent_dim)
    throw std::invalid_argument("train: the encoders of " + manifest_path + " send " +
                                std::to_string(m.latent_dim) + " values, training asks for " +
                                std::to_string(latent_dim));
  *trained_with = m.training;
  return ManifestEncoders(m, manifest_path);
}

// The stage-1 keys of `from` (how the encoders were trained) into `to`.
void CopyStage1Keys(const TrainingConfig& from, TrainingConfig& to) {
  to.dropout = from.dropout;
  to.beta = from.beta;
  to.ib_mse_units = from.ib_mse_units;
  to.stage1_lr = from.stage1_lr;
  to.stage1_batch = from.stage1_batch;
  to.stage1_max_epochs = from.stage1_max_epochs;
  to.stage1_patience = from.stage1_patience;
  to.stage1_plateau_epochs = from.stage1_plateau_epochs;
  to.stage1_min_samples_per_epoch = from.stage1_min_samples_per_epoch;
  to.stage1_max_samples_per_epoch = from.stage1_max_samples_per_epoch;
  to.stage1_max_validation_samples = from.stage1_max_validation_samples;
  to.stage1_label_gate_m = from.stage1_label_gate_m;
  to.stage1_label_gate_deg = from.stage1_label_gate_deg;
  to.camera_stereo_branches = from.camera_stereo_branches;
  to.camera_eye_pool_side = from.camera_eye_pool_side;
  to.camera_roi_geometry = from.camera_roi_geometry;
  to.point_frame = from.point_frame;
  to.point_norm = from.point_norm;
}

core::Json EvaluationJson(const Evaluation& ev) {
  core::Json j = core::Json::object();
  for (const auto& [key, rmse] : ev.rmse_m)
    j[key] = {{"rmse_m", std::isfinite(rmse) ? core::Json(rmse) : core::Json(nullptr)},
              {"windows", ev.windows.at(key)}};
  return j;
}

}  // namespace

bool ObservationHoldsTarget(const Sample& s) {
  if (s.camera) {
    if (!s.camera->detected) return false;
    const Eigen::Vector3d u = s.camera->bearing_left_w.normalized();
    const Eigen::Vector3d to_truth = s.truth_m - s.camera->eye_left_w;
    return to_truth.dot(u) > 0.0 && (to_truth - to_truth.dot(u) * u).norm() <= kCameraHoldsTargetM;
  }
  if (!s.points) return false;
  const double radius = s.modality == Modality::kLidar ? kLidarHoldsTargetM : kRadarHoldsTargetM;
  for (std::size_t i = 0; i < s.points->count(); ++i)
    if ((PointAt(*s.points, i) - s.truth_m).norm() <= radius) return true;
  return false;
}

Eigen::Vector3d TrivialEstimate(const Sample& s) {
  if (s.camera) {
    const double range = (s.truth_m - s.camera->eye_left_w).norm();
    return s.camera->eye_left_w + range * s.camera->bearing_left_w.normalized();
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  const std::size_t n = s.points ? s.points->count() : 0;
  for (std::size_t i = 0; i < n; ++i) centroid += PointAt(*s.points, i);
  return n ? Eigen::Vector3d(centroid / static_cast<double>(n)) : centroid;
}

std::map<std::string, Evaluation> OnCommonWindows(
    const std::map<std::string, Evaluation>& by_method) {
  std::map<std::string, Evaluation> out;
  if (by_method.empty()) return out;
  const Evaluation& first = by_method.begin()->second;
  for (const auto& [key, unused] : first.rmse_m) {
    // The windows of the first method that every other method counted too.
    std::vector<std::pair<std::size_t, std::int64_t>> common;
    const auto mine = first.squared_error_m2.find(key);
    if (mine != first.squared_error_m2.end())
      for (const auto& [window, e] : mine->second) {
        bool everyone = true;
        for (const auto& [method, ev] : by_method) {
          const auto theirs = ev.squared_error_m2.find(key);
          everyone =
              everyone && theirs != ev.squared_error_m2.end() && theirs->second.count(window) > 0;
        }
        if (everyone) common.push_back(window);
      }
    for (const auto& [method, ev] : by_method) {
      double sum = 0.0;
      for (const auto& window : common) sum += ev.squared_error_m2.at(key).at(window);
      Evaluation& o = out[method];
      o.windows[key] = common.size();
      o.rmse_m[key] = common.empty() ? std::numeric_limits<double>::quiet_NaN()
                                     : std::sqrt(sum / static_cast<double>(common.size()));
    }
  }
  return out;
}

void TrainOptions::Validate() const {
  try {
    CheckTrainingConfig(*this, "TrainOptions");
  } catch (const core::ConfigError& e) {
    throw std::invalid_argument(e.what());
  }
  const auto require = [](bool ok, const char* field, const std::string& rule) {
    if (!ok) throw std::invalid_argument(std::string("TrainOptions: ") + field + " " + rule);
  };
  require(latent_dim >= 2 && latent_dim % 2 == 0, "latent_dim", "must be even and >= 2");
  require(window_s > 0 && std::isfinite(window_s), "window_s", "must be > 0");
  require(!anchored_head || fusion == FusionKind::kUavLoc, "anchored_head",
          "extends the paper's fusion only (fusion \"uavloc\")");
  require(!method.empty(), "method", "must name the method");
}

namespace {

// test_estimates.csv: each method's estimate in every counted test window
// (the heads', and the classical methods' when scored), per modality subset
// (what Fig. 15's beams are steered at).
void WriteTestEstimates(const TrainReport& r, const std::string& path) {
  std::ostringstream f;
  f << "method,subset,episode,window,x_m,y_m,z_m,true_x_m,true_y_m,true_z_m,arrived\n";
  f.precision(9);
  for (const auto& [method, ev] : r.test)
    for (const auto& [subset, windows] : ev.position_m)
      for (const auto& [at, p] : windows)
        f << method << ',' << subset << ',' << at.first << ',' << at.second + 1 << ','
          << p.estimate_m.x() << ',' << p.estimate_m.y() << ',' << p.estimate_m.z() << ','
          << p.truth_m.x() << ',' << p.truth_m.y() << ',' << p.truth_m.z() << ','
          << (p.arrived ? ModalitySubsetName(p.arrived) : "none") << '\n';
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << f.str();
  if (!out) throw std::runtime_error(path + ": cannot write");
}

// Each episode's window is the training's.
void CheckEpisodes(const Dataset& data, const TrainOptions& o) {
  if (data.train.empty() || data.validation.empty())
    throw std::invalid_argument("train: need at least one training and one validation episode");
  for (const auto* part : {&data.train, &data.validation, &data.test})
    for (const Episode& e : *part)
      if (std::abs(e.window_s - o.window_s) > 1e-12)
        throw std::invalid_argument("train: episode \"" + e.label + "\" has " +
                                    core::FormatNumber(e.window_s) + " s windows, training " +
                                    core::FormatNumber(o.window_s) + " s");
}

// The edge network's configuration (both heads') from the training options.
UavLocModelConfig EdgeConfigOf(const TrainOptions& o, const IbNormalization& norm) {
  UavLocModelConfig config;
  config.latent_dim = o.latent_dim;
  config.window_s = o.window_s;
  config.d_model = o.d_model;
  config.layers = o.layers;
  config.temporal = o.temporal;
  config.lambda_init = o.mica_lambda_init;
  config.tau_origin = o.te_align_tau_origin;
  config.alignment = o.alignment;
  config.fusion = o.fusion;
  config.madw = o.madw;
  config.mica = o.mica;
  config.position_centre_m = norm.centre_m;
  config.position_scale_m = norm.scale_m;
  return config;
}

// The test episodes by weather (AlignAll keeps the episodes with windows,
// in order: test[i] is episodes[i]'s). Copies share the samples (SampleList).
struct TestParts {
  std::map<std::string, std::vector<std::size_t>> by_weather;  // weather -> indices
  std::map<std::string, std::vector<Episode>> episodes_by_weather;
  std::vector<Episode> episodes;
};

TestParts TestPartsOf(const Dataset& data) {
  TestParts t;
  for (const Episode& e : data.test)
    if (!e.window_truth.empty()) {
      t.by_weather[WeatherOf(e)].push_back(t.episodes.size());
      t.episodes_by_weather[WeatherOf(e)].push_back(e);
      t.episodes.push_back(e);
    }
  return t;
}

// The classical methods on the test episodes, all and by weather.
void ScoreClassical(const TrainOptions& o, const TestParts& t, bool have_test,
                    TrainReport& report) {
  for (const auto& [weather, episodes] : t.episodes_by_weather)
    report.test_weather_episodes[weather] = episodes.size();
  for (const Episode& e : t.episodes)
    report.test_episodes.push_back({e.index, e.label, WeatherOf(e)});
  if (!o.score_classical || !have_test) return;
  for (auto& [method, ev] : o.score_classical(t.episodes)) report.test[method] = std::move(ev);
  for (const auto& [weather, episodes] : t.episodes_by_weather)
    for (auto& [method, ev] : o.score_classical(episodes))
      report.test_by_weather[method][weather] = std::move(ev);
}

// Stage 2: each edge head asked for, from the generator state stage 1 left
// (trained alone or beside the other, the same head), scored on the test
// windows and saved into `out`.
void TrainHeads(const std::vector<WindowSequence>& train, const std::vector<WindowSequence>& val,
                const std::vector<WindowSequence>& test, const TestParts& parts,
                const UavLocModelConfig& config, const TrainOptions& o, const ModelManifest& m,
                const fs::path& out, TrainReport& report) {
  at::Generator generator = at::detail::getDefaultCPUGenerator();
  const torch::Tensor generator_state = generator.get_state();
  for (const bool anchored : {false, true}) {
    if (!(anchored ? o.anchored_head : o.paper_head)) continue;
    generator.set_state(generator_state);
    UavLocModelConfig head = config;
    head.anchored = anchored;
    if (anchored && o.offset_calibration_radius_m > 0.0) {
      head.candidate_offset_m = CandidateOffsets(train, head, o.offset_calibration_radius_m);
      report.candidate_offset_m = head.candidate_offset_m;
    }
    const std::string& file = anchored ? m.anchored_edge : m.edge;
    StageReport stage;
    UavLocModel model =
        TrainFusion(train, val, head, o, (out / "checkpoints" / file).string(), stage);
    report.stages.push_back(stage);
    if (!test.empty()) {
      const std::string method = anchored ? "uavloc_anchored" : o.method;
      report.test[method] = Evaluate(model, test);
      for (const auto& [weather, indices] : parts.by_weather) {
        std::vector<WindowSequence> part;
        for (std::size_t i : indices) part.push_back(test[i]);
        report.test_by_weather[method][weather] = Evaluate(model, part);
      }
    }
    SaveUavLocModel(model, (out / file).string());
  }
}

// The information limit and the comparisons on common windows (issue 41):
// each decoder alone, the observations holding the target, every method on
// the windows all of them answered.
void ScoreDiagnostics(const Dataset& data, std::vector<IbCcModel>& encoders, const TeAlign& align,
                      TrainReport& report) {
  if (!data.test.empty()) report.test_decoder = DecoderScores(encoders, data.test, align);
  if (!data.validation.empty())
    report.validation_decoder = DecoderScores(encoders, data.validation, align);
  for (const Episode& e : data.test)
    for (const Sample& smp : e.samples)
      for (const std::string& w : {std::string("all"), WeatherOf(e)}) {
        TrainReport::SentCounts& c =
            report.test_sent[kPartNames[static_cast<int>(smp.modality)]][w];
        ++c.sent;
        c.holding_target += ObservationHoldsTarget(smp);
      }
}

// Every method on the windows all of them answered, all and by weather.
void ScoreOnCommonWindows(TrainReport& report) {
  report.test_common = OnCommonWindows(report.test);
  std::map<std::string, std::map<std::string, Evaluation>> by_weather;  // weather -> method
  for (const auto& [method, weathers] : report.test_by_weather)
    for (const auto& [weather, ev] : weathers) by_weather[weather][method] = ev;
  for (const auto& [weather, methods] : by_weather)
    for (auto& [method, ev] : OnCommonWindows(methods))
      report.test_by_weather_common[method][weather] = std::move(ev);
}

// The encoders, training_report.json, model.json and, last, the checksums
// over every file of the folder.
void WriteModelFolder(const fs::path& out, const ModelManifest& m,
                      const std::vector<IbCcModel>& encoders, const TrainReport& report,
                      const TrainOptions& o) {
  const std::string* names[kModalityCount] = {&m.camera, &m.lidar, &m.radar};
  for (int i = 0; i < kModalityCount; ++i)
    SaveIbCcModel(encoders[static_cast<std::size_t>(i)], (out / *names[i]).string(), m.note);
  fs::remove_all(out / "checkpoints");
  {
    const std::string text = ReportJson(report, o);
    const fs::path p = out / "training_report.json";
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f << text;
    if (!f) throw std::runtime_error(p.string() + ": cannot write");
  }
  WriteModelManifest(m, (out / "model.json").string());
  WriteModelChecksums(out.string());  // last: over every file of the folder
}

// Stage 1: the encoders not reused, trained modality by modality.
void TrainEncoders(const Dataset& data, const TrainOptions& o, const IbNormalization& norm,
                   const fs::path& checkpoints, std::vector<IbCcModel>& encoders,
                   TrainReport& report) {
  for (int m = 0; encoders.size() < kModalityCount; ++m) {
    StageReport stage;
    encoders.push_back(TrainEncoder(static_cast<Modality>(m), data, o, norm,
                                    (checkpoints / (std::string(kPartNames[m]) + ".json")).string(),
                                    stage));
    report.stages.push_back(stage);
  }
}

}  // namespace

TrainReport TrainUavLoc(const Dataset& data, const TrainOptions& o, const ModelManifest& manifest,
                        const std::string& out_dir) {
  o.Validate();
  const StopScope stop(o.check_stop);
  CheckEpisodes(data, o);
  torch::manual_seed(o.seed);
  std::vector<IbCcModel> encoders;
  std::optional<TrainingConfig> encoders_trained_with;
  if (!o.encoders_from.empty())
    encoders = LoadEncoders(o.encoders_from, o.latent_dim, &encoders_trained_with);
  std::vector<Eigen::Vector3d> positions;
  for (const Episode& e : data.train)
    positions.insert(positions.end(), e.window_truth.begin(), e.window_truth.end());
  const IbNormalization norm = encoders.empty() ? FitPositionNormalization(positions)
                                                : encoders.front()->config().normalization;

  const fs::path out(out_dir);
  fs::create_directories(out / "checkpoints");
  TrainReport report;
  report.split = data.split;
  report.encoders_from = o.encoders_from;
  TrainEncoders(data, o, norm, out / "checkpoints", encoders, report);

  const UavLocModelConfig config = EdgeConfigOf(o, norm);
  const TeAlign align(config.te_align());
  // Stage 1 only (no head asked for): no sequences to train on.
  const bool stage2 = o.paper_head || o.anchored_head;
  const std::vector<WindowSequence> train =
      stage2 ? AlignAll(data.train, encoders, align, norm) : std::vector<WindowSequence>{};
  const std::vector<WindowSequence> val =
      stage2 ? AlignAll(data.validation, encoders, align, norm) : std::vector<WindowSequence>{};
  const std::vector<WindowSequence> test = data.test.empty()
                                               ? std::vector<WindowSequence>{}
                                               : AlignAll(data.test, encoders, align, norm);
  const TestParts parts = TestPartsOf(data);
  ScoreClassical(o, parts, !test.empty(), report);

  ModelManifest m = manifest;
  m.latent_dim = o.latent_dim;
  m.window_s = o.window_s;
  m.training = static_cast<const TrainingConfig&>(o);
  // Stage 1 as the reused encoders were trained.
  if (encoders_trained_with) CopyStage1Keys(*encoders_trained_with, *m.training);
  m.edge = o.paper_head ? "uavloc.pt" : "";
  m.anchored_edge = o.anchored_head ? "uavloc_anchored.pt" : "";
  TrainHeads(train, val, test, parts, config, o, m, out, report);
  ScoreDiagnostics(data, encoders, align, report);
  WriteTestEstimates(report, (out / "test_estimates.csv").string());
  ScoreOnCommonWindows(report);
  WriteModelFolder(out, m, encoders, report, o);
  return report;
}

std::map<std::string, Evaluation> EvaluateModel(const std::string& model_path,
                                                const std::vector<Episode>& episodes) {
  const std::string manifest_path = ModelManifestPath(model_path);
  const ModelManifest m = ReadModelManifest(manifest_path);
  std::vector<IbCcModel> encoders = ManifestEncoders(m, manifest_path);
  const IbNormalization& norm = encoders.front()->config().normalization;
  const EdgeHeads heads = ReadEdgeHeads(m, manifest_path);
  std::map<std::string, Evaluation> out;
  std::vector<WindowSequence> sequences;
  const std::string paper_method = VariantMethod(m.variant);
  for (const auto& [method, path] : {std::pair{paper_method.c_str(), &heads.paper},
                                     std::pair{"uavloc_anchored", &heads.anchored}}) {
    if (path->empty()) continue;
    UavLocModel model = LoadUavLocModel(*path);
    if (sequences.empty()) sequences = AlignAll(episodes, encoders, model->te_align(), norm);
    out[method] = Evaluate(model, sequences);
  }
  return out;
}

std::map<std::string, DecoderScore> EvaluateDecoders(const std::string& model_path,
                                                     const std::vector<Episode>& episodes) {
  const std::string manifest_path = ModelManifestPath(model_path);
  const ModelManifest m = ReadModelManifest(manifest_path);
  std::vector<IbCcModel> encoders = ManifestEncoders(m, manifest_path);
  TeAlignConfig windows;
  windows.latent_dim = m.latent_dim;
  windows.window_s = m.window_s;
  return DecoderScores(encoders, episodes, TeAlign(windows));
}

namespace {

// TrainReport::test_decoder / validation_decoder as JSON, by modality name.
core::Json DecoderScoresJson(const std::map<std::string, DecoderScore>& scores) {
  const auto number = [](double v) {
    return std::isfinite(v) ? core::Json(v) : core::Json(nullptr);
  };
  core::Json decoder = core::Json::object();
  for (const auto& [modality, d] : scores)
    decoder[modality] = {
        {"rmse_m", number(d.rmse_m)},
        {"observations", d.observations},
        {"on_target", {{"rmse_m", number(d.on_target_rmse_m)}, {"observations", d.on_target}}},
        {"off_target", {{"rmse_m", number(d.off_target_rmse_m)}, {"observations", d.off_target}}},
        {"centroid_on_target_m", number(d.centroid_on_target_m)}};
  return decoder;
}

// Each method's "all" windows of test episode `i` alone.
std::map<std::string, Evaluation> EpisodeEvaluations(const std::map<std::string, Evaluation>& test,
                                                     std::size_t i) {
  std::map<std::string, Evaluation> out;
  for (const auto& [method, ev] : test) {
    Evaluation& o = out[method];
    double sum = 0.0;
    auto& mine = o.squared_error_m2["all"];
    if (const auto all = ev.squared_error_m2.find("all"); all != ev.squared_error_m2.end())
      for (const auto& [window, e] : all->second)
        if (window.first == i) {
          mine[window] = e;
          sum += e;
        }
    o.windows["all"] = mine.size();
    o.rmse_m["all"] = mine.empty() ? std::numeric_limits<double>::quiet_NaN()
                                   : std::sqrt(sum / static_cast<double>(mine.size()));
  }
  return out;
}

// TrainReport::test_episodes as JSON: per episode, each method over its own
// windows and over the windows every method counted.
core::Json TestEpisodesJson(const TrainReport& r) {
  core::Json episodes = core::Json::array();
  for (std::size_t i = 0; i < r.test_episodes.size(); ++i) {
    const std::map<std::string, Evaluation> own = EpisodeEvaluations(r.test, i);
    core::Json methods = core::Json::object(), common = core::Json::object();
    for (const auto& [method, ev] : own) methods[method] = EvaluationJson(ev)["all"];
    for (const auto& [method, ev] : OnCommonWindows(own))
      common[method] = EvaluationJson(ev)["all"];
    const int index = r.test_episodes[i].index;
    episodes.push_back({{"episode", index >= 0 ? core::Json(index) : core::Json(nullptr)},
                        {"label", r.test_episodes[i].label},
                        {"weather", r.test_episodes[i].weather},
                        {"methods", methods},
                        {"common_windows", common}});
  }
  return episodes;
}

}  // namespace

std::string ReportJson(const TrainReport& r, const TrainOptions& o) {
  core::Json j = core::Json::object();
  j["seed"] = o.seed;
  j["split"] = DataSplitName(r.split);
  j["latent_dim"] = o.latent_dim;
  j["bottleneck"] = o.bottleneck == IbBottleneck::kIb ? "ib" : "mlp";
  core::Json heads = core::Json::array();
  if (o.paper_head) heads.push_back("paper");
  if (o.anchored_head) heads.push_back("anchored");
  j["heads"] = heads;
  if (o.anchored_head) {
    j["selection_loss"] = {{"weight", o.selection_weight},
                           {"radius_m", o.selection_radius_m},
                           {"filter_preference_m", o.filter_preference_m}};
    j["position_loss"] = o.mixture_loss ? "mixture" : "mean";
    j["offset_calibration_radius_m"] = o.offset_calibration_radius_m;
    core::Json offsets = core::Json::array();
    for (const Eigen::Vector3d& v : r.candidate_offset_m) offsets.push_back({v.x(), v.y(), v.z()});
    j["candidate_offset_m"] = offsets;
  }
  j["method"] = o.method;
  j["edge"] = {{"temporal", TemporalKindName(o.temporal)},
               {"alignment", AlignmentName(o.alignment)},
               {"fusion", FusionKindName(o.fusion)},
               {"madw", o.madw},
               {"mica", o.mica}};
  if (!r.encoders_from.empty()) j["encoders_from"] = r.encoders_from;
  j["stage2_plateau_epochs"] = o.stage2_plateau_epochs;
  j["learning_rate"] = {{"stage1", o.stage1_lr}, {"stage2", o.stage2_lr}};
  j["stage1_label_gate"] = {{"m", o.stage1_label_gate_m}, {"deg", o.stage1_label_gate_deg}};
  core::Json stages = core::Json::array();
  for (const StageReport& s : r.stages)
    stages.push_back({{"name", s.name},
                      {"train_items", s.train_items},
                      {"label_gated_items", s.label_gated_items},
                      {"validation_items", s.validation_items},
                      {"epochs", s.epochs},
                      {"best_epoch", s.best_epoch},
                      {"initial_validation_loss", s.initial_validation_loss},
                      {"best_validation_loss", s.best_validation_loss},
                      {"seconds", s.seconds}});
  j["stages"] = stages;
  core::Json test = core::Json::object();
  for (const auto& [method, ev] : r.test) test[method] = EvaluationJson(ev);
  j["test"] = test;
  j["test_decoder"] = DecoderScoresJson(r.test_decoder);
  j["validation_decoder"] = DecoderScoresJson(r.validation_decoder);
  core::Json sent = core::Json::object();
  for (const auto& [modality, weathers] : r.test_sent)
    for (const auto& [weather, c] : weathers)
      sent[modality][weather] = {{"sent", c.sent}, {"holding_target", c.holding_target}};
  j["test_sent"] = sent;
  core::Json by_weather = core::Json::object();
  for (const auto& [method, weathers] : r.test_by_weather)
    for (const auto& [weather, ev] : weathers) by_weather[method][weather] = EvaluationJson(ev);
  j["test_by_weather"] = by_weather;
  // The same on the windows every method counted.
  core::Json common = core::Json::object();
  for (const auto& [method, ev] : r.test_common) common[method] = EvaluationJson(ev);
  j["test_common_windows"] = common;
  core::Json by_weather_common = core::Json::object();
  for (const auto& [method, weathers] : r.test_by_weather_common)
    for (const auto& [weather, ev] : weathers)
      by_weather_common[method][weather] = EvaluationJson(ev);
  j["test_by_weather_common_windows"] = by_weather_common;
  core::Json weather_episodes = core::Json::object();
  for (const auto& [weather, n] : r.test_weather_episodes) weather_episodes[weather] = n;
  j["test_weather_episodes"] = weather_episodes;
  j["test_episodes"] = TestEpisodesJson(r);
  return j.dump(2) + "\n";
}

}  // namespace uavsim::pipeline
