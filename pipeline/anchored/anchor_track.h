// `anchor_track`: the anchored model's anchor filter (anchor_filter.h, the
// IMM of a coordinated turn and a constant velocity) run alone as a
// localization method, on exactly the anchors an anchored model's tracker
// feeds it (anchors.h: every anchor stamped in a window, in capture order,
// at the window's deadline). Our extension, not the paper's: it shows what
// `uavloc_anchored`'s learned head adds over its own filter's track.
//
// Answers from the first window whose end finds the track confirmed (its
// position standard deviation at most kConfirmedSigma_m, the rule
// EdgeLocalizer::WaitForTrack uses), as the EKF answers only once a track is
// confirmed; then the track predicted to each window's end, and the last
// estimate held while the filter has none (it stops predicting
// AnchorFilter::kMaxPredict_s after its last ranging fix), as the EKF holds
// a lost track's. World ENU, metres, seconds. Plain C++ (Eigen only).
// Deterministic: no randomness.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>

#include "pipeline/anchored/anchor_filter.h"
#include "pipeline/anchored/geometric_anchor.h"

namespace uavsim::pipeline {

class AnchorTrack {
 public:
  // Throws std::invalid_argument for window_s not finite and > 0.
  explicit AnchorTrack(double window_s);

  // Window k (ending at k * window_s) and every anchor stamped in it (per
  // modality, any order: they are applied in capture order, ties in
  // Modality order). Windows must increase; skipped ones count as empty.
  // Throws std::invalid_argument for k not after the previous window.
  std::optional<Eigen::Vector3d> OnWindow(std::int64_t k, const WindowAnchors& arrived);
  void Reset();

  static constexpr double kConfirmedSigma_m = 1.0;

 private:
  double window_s_;
  AnchorFilter filter_{AnchorFilter::Motion::kImm};
  std::optional<std::int64_t> last_window_;
  std::optional<Eigen::Vector3d> last_;  // the latest answer (held while the filter has none)
};

}  // namespace uavsim::pipeline
