#include "pipeline/multitarget/per_track_uavloc.h"

#include <utility>

namespace uavsim::pipeline {

PerTrackUavLoc::PerTrackUavLoc(double window_s, EdgeFactory make_edge)
    : tracker_(window_s), make_edge_(std::move(make_edge)) {}

std::unique_ptr<EdgeLocalizer> PerTrackUavLoc::TakeEdge() {
  if (spare_.empty()) return make_edge_();
  std::unique_ptr<EdgeLocalizer> edge = std::move(spare_.back());
  spare_.pop_back();
  return edge;
}

std::vector<TrackEstimate> PerTrackUavLoc::OnWindow(std::int64_t k,
                                                    const std::vector<Detection>& detections) {
  tracker_.OnWindow(k, detections);
  const auto& assigned = tracker_.assigned();
  // Deleted tracks give their networks back, reset.
  for (auto it = edges_.begin(); it != edges_.end();) {
    if (assigned.count(it->first)) {
      ++it;
      continue;
    }
    it->second->Reset();
    spare_.push_back(std::move(it->second));
    it = edges_.erase(it);
  }
  std::vector<TrackEstimate> out;
  for (const auto& [label, indices] : assigned) {
    std::unique_ptr<EdgeLocalizer>& edge = edges_[label];
    if (!edge) edge = TakeEdge();
    WindowInputs in;
    in.window = k;
    for (std::size_t i : indices) {
      const Detection& d = detections[i];
      if (d.latent.empty()) continue;
      in.frames[static_cast<std::size_t>(d.modality)].push_back(
          {d.t_capture_s, d.latent, d.anchor});
    }
    const auto p = edge->OnWindow(in);
    if (p && tracker_.confirmed(label)) out.push_back({label, *p});
  }
  return out;
}

}  // namespace uavsim::pipeline
