// The edge server's UAVLoc localizer as the engine sees it: load a trained
// model, hand it each window's latent packets, get a position. No LibTorch in
// this header (the engine must not include <torch/torch.h>): the model lives
// behind a pointer to an implementation.
//
// Call pipeline::InitTorch (pipeline/torch_runtime.h) before Load: the thread
// count it fixes is the one inference runs on.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "pipeline/edge/te_align.h"

namespace uavsim::pipeline {

class EdgeLocalizer {
 public:
  // Reads the model at `path` and its configuration at `path` + ".json"
  // (see uavloc_model.h). Throws core::ConfigError naming the file for a
  // missing, malformed or mismatched model.
  static std::unique_ptr<EdgeLocalizer> Load(const std::string& path);
  // Fresh untrained weights (from LibTorch's generator) for a latent size z
  // and window t^w, the paper's or the anchored head, other sizes at their
  // defaults: for benchmarks and tests. Throws std::invalid_argument for an
  // invalid size.
  static std::unique_ptr<EdgeLocalizer> Create(int latent_dim, double window_s,
                                               bool anchored = false);
  ~EdgeLocalizer();
  EdgeLocalizer(const EdgeLocalizer&) = delete;
  EdgeLocalizer& operator=(const EdgeLocalizer&) = delete;

  // Runs at window k's deadline on whatever arrived for it (late and lost
  // packets are simply absent; all three modalities may be). Windows must
  // come in increasing k; skipped windows count as empty. Returns the UAV
  // position in world ENU metres, or nothing until a window since Load or
  // Reset has held at least one modality (before that the network has seen
  // no measurement at all). Throws std::invalid_argument for k not after
  // the previous window, a latent whose size is not latent_dim(), or a
  // non-finite latent value.
  // With WaitForTrack(true) an anchored model answers only from the first
  // window in which its anchor filter holds a confirmed track
  // (pipeline/anchored/anchor_filter.h: started at a LiDAR fix that agreed with the camera's
  // ray, or at two radar fixes that did and agreed with each other, and
  // known to kConfirmedSigma_m at the window's end; before that its range
  // is a guess, metres off), as the EKF answers only once a track is
  // confirmed.
  std::optional<Eigen::Vector3d> OnWindow(const WindowInputs& window);
  void WaitForTrack(bool wait);
  // A track's position standard deviation (sqrt of its covariance's trace)
  // at or below which it is confirmed: a fresh start's unknown velocity
  // (AnchorFilter::kStartSpeedSigma_mps) puts it above until a second fix.
  static constexpr double kConfirmedSigma_m = 1.0;

  // Forgets the track (and any fix seen): the next window starts from a
  // zero state.
  void Reset();

  int latent_dim() const;  // z the model expects from every node
  // Whether the model uses the nodes' geometric anchors (pipeline/anchored/anchors.h),
  // which the nodes then send with their latents.
  bool anchored() const;
  double window_s() const;  // t^w the model was trained with

 private:
  struct Impl;
  explicit EdgeLocalizer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::pipeline
