#include "pipeline/localization_method.h"

#include <utility>

#include "pipeline/anchored/anchor_track.h"
#include "pipeline/baselines/ekf.h"
#include "pipeline/edge/edge_localizer.h"
#include "pipeline/edge/scripted_edge.h"
#include "pipeline/multitarget/per_track_uavloc.h"
#include "pipeline/multitarget/target_tracker.h"
#include "pipeline/pipeline_config.h"

namespace uavsim::pipeline {
namespace {

class EkfLocalization final : public LocalizationMethod {
 public:
  explicit EkfLocalization(std::unique_ptr<Ekf> ekf)
      : LocalizationMethod("ekf", {/*arrivals=*/true, false, false}, true), ekf_(std::move(ekf)) {}

 private:
  void DoObserve(const Arrival& a) override {
    if (a.camera) ekf_->Observe(*a.node_id, *a.camera);
    if (a.points) ekf_->Observe(*a.node_id, *a.points);
  }
  std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) override {
    return ekf_->EstimateAt(w.t_end_s);
  }
  std::unique_ptr<Ekf> ekf_;
};

class AnchorTrackLocalization final : public LocalizationMethod {
 public:
  explicit AnchorTrackLocalization(double window_s)
      : LocalizationMethod("anchor_track", {false, false, /*anchors=*/true}, true),
        track_(window_s) {}

 private:
  std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) override {
    return track_.OnWindow(w.k, w.anchors);
  }
  AnchorTrack track_;
};

class MttLocalization final : public LocalizationMethod {
 public:
  MttLocalization(double window_s, TargetTracker::Association association)
      : LocalizationMethod(association == TargetTracker::Association::kJpda ? "mtt_jpda" : "mtt",
                           {false, false, false, /*detections=*/true}, true),
        tracker_(window_s, association) {}

 private:
  std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) override {
    tracks_ = tracker_.OnWindow(w.k, w.detections);
    if (tracks_.empty()) return std::nullopt;
    return tracks_.front().position_m;  // the oldest confirmed track
  }
  std::optional<std::vector<TrackEstimate>> DoTracks() const override { return tracks_; }
  TargetTracker tracker_;
  std::vector<TrackEstimate> tracks_;
};

class PerTrackLocalization final : public LocalizationMethod {
 public:
  PerTrackLocalization(double window_s, PerTrackUavLoc::EdgeFactory make_edge)
      : LocalizationMethod("uavloc_per_track",
                           {false, /*latents=*/true, false,
                            /*detections=*/true},
                           true),
        per_track_(window_s, std::move(make_edge)) {}

 private:
  std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) override {
    tracks_ = per_track_.OnWindow(w.k, w.detections);
    if (tracks_.empty()) return std::nullopt;
    return tracks_.front().position_m;  // the oldest confirmed track's
  }
  std::optional<std::vector<TrackEstimate>> DoTracks() const override { return tracks_; }
  PerTrackUavLoc per_track_;
  std::vector<TrackEstimate> tracks_;
};

class LearnedLocalization final : public LocalizationMethod {
 public:
  LearnedLocalization(std::string name, std::unique_ptr<EdgeLocalizer> edge, int modalities,
                      bool anchored)
      : LocalizationMethod(std::move(name), {false, /*latents=*/true, anchored},
                           modalities == kModalitySubsets),
        edge_(std::move(edge)),
        modalities_(modalities) {}

 private:
  std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) override {
    if (modalities_ == kModalitySubsets) return edge_->OnWindow(w.latents);
    WindowInputs fed;  // the modalities the method is fed
    fed.window = w.latents.window;
    for (int m = 0; m < core::kModalityCount; ++m)
      if (modalities_ & (1 << m)) fed.frames[m] = w.latents.frames[m];
    return edge_->OnWindow(fed);
  }
  std::unique_ptr<EdgeLocalizer> edge_;
  int modalities_;
};

class ScriptedLocalization final : public LocalizationMethod {
 public:
  ScriptedLocalization(std::string name, std::unique_ptr<ScriptedEdge> edge)
      : LocalizationMethod(std::move(name), {false, /*latents=*/true, false}, true),
        edge_(std::move(edge)) {}

 private:
  std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) override {
    try {
      return edge_->OnWindow(w.latents);
    } catch (const ScriptedEdgeFailure& e) {
      throw ScriptedEdgeFailure("method " + name() + ": " + e.what(), e.traceback());
    }
  }
  std::unique_ptr<ScriptedEdge> edge_;
};

}  // namespace

std::unique_ptr<LocalizationMethod> MakeEkfMethod(std::unique_ptr<Ekf> ekf) {
  return std::make_unique<EkfLocalization>(std::move(ekf));
}

std::unique_ptr<LocalizationMethod> MakeAnchorTrackMethod(double window_s) {
  return std::make_unique<AnchorTrackLocalization>(window_s);
}

std::unique_ptr<LocalizationMethod> MakeMttMethod(double window_s, bool jpda) {
  return std::make_unique<MttLocalization>(
      window_s, jpda ? TargetTracker::Association::kJpda : TargetTracker::Association::kGnn);
}

std::unique_ptr<LocalizationMethod> MakePerTrackMethod(
    double window_s, std::function<std::unique_ptr<EdgeLocalizer>()> make_edge) {
  return std::make_unique<PerTrackLocalization>(window_s, std::move(make_edge));
}

std::unique_ptr<LocalizationMethod> MakeLearnedMethod(std::string name,
                                                      std::unique_ptr<EdgeLocalizer> edge,
                                                      int modalities, bool anchored) {
  return std::make_unique<LearnedLocalization>(std::move(name), std::move(edge), modalities,
                                               anchored);
}

std::unique_ptr<LocalizationMethod> MakeScriptedMethod(std::string name,
                                                       std::unique_ptr<ScriptedEdge> edge) {
  return std::make_unique<ScriptedLocalization>(std::move(name), std::move(edge));
}

}  // namespace uavsim::pipeline
