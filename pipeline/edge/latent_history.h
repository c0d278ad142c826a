// The last L alignment windows' latents as a user's edge model is given them
// (the contract of pipeline/edge/scripted_edge.h), packed into plain float
// arrays: the TorchScript methods wrap them in tensors, the Python methods
// (apps/python) in NumPy arrays. No LibTorch here.
//
//   latents   [L, 3, F, z]  window l (0 oldest, L - 1 the newest), modality
//                           m (core::Modality), frame f in capture order
//   offsets_s [L, 3, F]     capture time minus the window's start, seconds
//   mask      [L, 3, F]     1 for a frame, 0 for padding
// Windows before the first pushed, and windows skipped between two pushes,
// are padding. F is the largest frame count of any modality in the L
// windows (at least 1). Row-major (C order). Deterministic.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "pipeline/edge/te_align.h"

namespace uavsim::pipeline {

struct PackedWindows {
  int windows = 1;      // L
  int frames = 1;       // F
  int latent_dim = 16;  // z
  std::vector<float> latents;
  std::vector<float> offsets_s;
  std::vector<float> mask;
};

class LatentHistory {
 public:
  // history_windows >= 1, latent_dim >= 1, window_s > 0 (std::invalid_argument else).
  LatentHistory(int history_windows, int latent_dim, double window_s);

  // Window k's inputs (windows in increasing k). Throws std::invalid_argument
  // for a k not after the previous one or a latent of another size.
  void Push(const WindowInputs& window);
  // Whether any window pushed so far held a frame.
  bool has_seen_data() const { return has_seen_data_; }
  PackedWindows Pack() const;

  int history_windows() const { return history_; }
  int latent_dim() const { return latent_dim_; }

 private:
  int history_;
  int latent_dim_;
  double window_s_;
  std::deque<WindowInputs> windows_;  // the last `history_` windows, oldest first
  std::optional<std::int64_t> last_window_;
  bool has_seen_data_ = false;
};

}  // namespace uavsim::pipeline
