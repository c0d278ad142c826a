// A user's edge model as a localization method (bring your own model): a
// TorchScript file, scripted or traced in Python with the python3-torch that
// matches our LibTorch (1.13.1), run at each window's deadline on exactly
// what `uavloc` is given: the IB-CC latents that arrived on time, per
// modality, with their capture times. No LibTorch in this header.
//
// The module's contract (checked by Load):
//   forward(latents: Tensor, offsets_s: Tensor, mask: Tensor) -> Tensor
//     latents   float32 [L, 3, F, z]  window l (0 oldest, L - 1 the window
//                                     being estimated), modality m (0 camera,
//                                     1 LiDAR, 2 radar: core::Modality), frame
//                                     f of that modality in the window in
//                                     capture order, the node's latent mu
//     offsets_s float32 [L, 3, F]     capture time minus the window's start
//                                     (k - 1) t^w, seconds, in [0, t^w)
//     mask      float32 [L, 3, F]     1 for a frame, 0 for padding
//     returns   3 numbers (shape [3] or [1, 3]): the target's position at the
//               end of window L - 1, world ENU metres; a non-finite value
//               (or one more than 1 km outside the scenario's bounds) is
//               no estimate for this window, counted in metrics.json's
//               rejected_estimates
//   L is the module's integer attribute `history_windows` (default 1): the
//   windows before the run's first are all padding. F is the largest number
//   of frames any modality has in any of the L windows (at least 1); z is
//   the scenario's /pipeline/latent_dim. The frames of a window are those
//   captured in it that reached the edge by its deadline (lost and late ones
//   are absent), as pipeline/edge/te_align.h's WindowInputs holds them.
// The module must be a function of its inputs (no state kept between calls):
// Load calls it once on padding to check the signature.
//
// Determinism: inference on LibTorch's intra-op threads as InitTorch set them
// (call pipeline::InitTorch first); the same inputs give the same output.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "pipeline/edge/te_align.h"

namespace uavsim::pipeline {

// The model failed while a run was going (it raised, or its output could
// not be read as 3 numbers): what() is one line, "FILE: forward failed at
// window K: WHAT" (WHAT: the first line of LibTorch's message, or the
// exception the model raised); traceback() is LibTorch's whole message.
class ScriptedEdgeFailure : public std::runtime_error {
 public:
  ScriptedEdgeFailure(const std::string& line, std::string traceback);
  const std::string& traceback() const { return traceback_; }

 private:
  std::string traceback_;
};

class ScriptedEdge {
 public:
  // Loads the TorchScript file at `path` for latents of `latent_dim` values
  // and windows of `window_s`. Throws std::invalid_argument with one line
  // saying what was expected (the file is missing, not TorchScript, has no
  // forward of three tensors, returns other than 3 numbers, or a bad
  // history_windows).
  static std::unique_ptr<ScriptedEdge> Load(const std::string& path, int latent_dim,
                                            double window_s);
  ~ScriptedEdge();
  ScriptedEdge(const ScriptedEdge&) = delete;
  ScriptedEdge& operator=(const ScriptedEdge&) = delete;

  // Window k's estimate (windows in increasing k; skipped ones count as
  // empty). Nothing until a window has held at least one frame; a
  // non-finite value as the model returned it (the run counts it as no
  // estimate, sim/window_scorer.h). Throws std::invalid_argument for k not
  // after the previous window or a latent of the wrong size,
  // ScriptedEdgeFailure when the model fails.
  std::optional<Eigen::Vector3d> OnWindow(const WindowInputs& window);

  int history_windows() const;
  int latent_dim() const;

 private:
  struct Impl;
  explicit ScriptedEdge(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::pipeline
