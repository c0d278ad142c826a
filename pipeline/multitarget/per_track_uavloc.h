// `uavloc_per_track` (our extension of the paper, issue 46; listed in
// metrics.json's uavloc_model.extensions): the paper's pipeline run once per
// track of the multi-target tracker (target_tracker.h, the one `mtt` runs).
// Each live track has an edge network of its own (TE-Align, MADW, MICA,
// Mamba and the paper's head, with its own temporal state), fed each
// window the latents of the detections the tracker associated with that
// track (by their geometric anchors: its gates and assignment). It reports
// the confirmed tracks' regressed positions, labelled as the tracker's (a
// track whose network has no estimate yet has none). How it differs from
// the paper: the paper regresses one target from every latent that arrived;
// here the tracker chooses which latents each regression sees.
//
// Networks: made by the factory for a new track, or taken from those of
// deleted tracks after a Reset (the same weights; Reset forgets their
// state). Deterministic as the tracker and the networks are.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "pipeline/edge/edge_localizer.h"
#include "pipeline/multitarget/detection.h"
#include "pipeline/multitarget/target_tracker.h"

namespace uavsim::pipeline {

class PerTrackUavLoc {
 public:
  using EdgeFactory = std::function<std::unique_ptr<EdgeLocalizer>()>;
  // Throws std::invalid_argument for window_s not finite and > 0.
  PerTrackUavLoc(double window_s, EdgeFactory make_edge);

  // As TargetTracker::OnWindow, with each confirmed track's position the one
  // its network regressed (confirmed tracks without one left out).
  std::vector<TrackEstimate> OnWindow(std::int64_t k, const std::vector<Detection>& detections);

 private:
  std::unique_ptr<EdgeLocalizer> TakeEdge();

  TargetTracker tracker_;
  EdgeFactory make_edge_;
  std::map<std::uint32_t, std::unique_ptr<EdgeLocalizer>> edges_;  // per live track
  std::vector<std::unique_ptr<EdgeLocalizer>> spare_;              // of deleted tracks, reset
};

}  // namespace uavsim::pipeline
