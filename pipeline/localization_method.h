// One localization method at the edge (DESIGN.md: every edge method behind
// one interface). The edge server holds a list of them and knows no family:
// it tells each method of every message that reaches the edge on time (when
// the method takes arrivals) and, at each alignment window's deadline, asks
// it for the target's position at the window's end. The public methods are
// the server's; each family's work is its private Do... (ns-3's
// CalcRxPower / DoCalcRxPower). Families (factories below): `ekf` (the
// classical baseline), `anchor_track` (our anchored head's filter alone),
// `mtt` (the multi-target tracker), `uavloc_per_track` (the paper's network
// per track),
// the learned methods (uavloc, uavloc_anchored, the paper's variants and
// modality subsets: pipeline/model_catalog.h makes them) and users'
// TorchScript models.
//
// Frames and units: positions in world ENU metres, times in seconds of
// simulated time. Determinism: no method draws random numbers; each has its
// own state, so the order the server asks them in changes nothing.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/modality.h"
#include "pipeline/anchored/geometric_anchor.h"
#include "pipeline/edge/te_align.h"
#include "pipeline/multitarget/detection.h"
#include "pipeline/node/observations.h"

namespace uavsim::pipeline {

class Ekf;
class EdgeLocalizer;
class ScriptedEdge;

// A node's message that reached the edge on time, as the methods see it.
struct Arrival {
  const std::string* node_id = nullptr;
  core::Modality modality = core::Modality::kCamera;
  double t_capture_s = 0.0;
  // The pre-processed observation the node sent (null when it sent another kind).
  const CameraObservation* camera = nullptr;
  const PointObservation* points = nullptr;
};

// What arrived on time for window k, handed to every method at its deadline.
struct WindowArrivals {
  std::int64_t k = 1;    // the window covers (k-1) t^w <= t < k t^w
  double t_end_s = 0.0;  // k t^w: the time the estimate is for
  // The IB-CC latents (with their anchors), when a method needs latents.
  WindowInputs latents;
  // The geometric anchors (kNone left out), when a method needs anchors.
  WindowAnchors anchors;
  // Every observation of every message (the further ones too), in arrival
  // order, when a method needs detections.
  std::vector<Detection> detections;
};

// What a method needs of the nodes and the server.
struct MethodNeeds {
  bool arrivals = false;    // Observe on every arrival (the ekf)
  bool latents = false;     // the nodes run a trained model's IB-CC encoders
  bool anchors = false;     // the nodes send geometric anchors with their latents
  bool detections = false;  // every observation's anchor (and latent), for several targets
};

class LocalizationMethod {
 public:
  virtual ~LocalizationMethod() = default;
  LocalizationMethod(const LocalizationMethod&) = delete;
  LocalizationMethod& operator=(const LocalizationMethod&) = delete;

  // The name it is scored and written under (`/pipeline/methods`).
  const std::string& name() const { return name_; }
  const MethodNeeds& needs() const { return needs_; }
  // Whether its estimates steer a downlink beam (the single-modality
  // ablations steer none).
  bool steers_beam() const { return steers_beam_; }

  // An arrival on time (called only when needs().arrivals).
  void Observe(const Arrival& a) { DoObserve(a); }
  // Its estimate at window w's end, or nothing where it has none yet.
  // Windows come in increasing k.
  std::optional<Eigen::Vector3d> Estimate(const WindowArrivals& w) { return DoEstimate(w); }
  // After Estimate: a multi-target method's labelled estimates at the
  // window's end (its Estimate is one of them); nothing for a method that
  // localizes one target.
  std::optional<std::vector<TrackEstimate>> Tracks() const { return DoTracks(); }

 protected:
  LocalizationMethod(std::string name, MethodNeeds needs, bool steers_beam)
      : name_(std::move(name)), needs_(needs), steers_beam_(steers_beam) {}

 private:
  virtual void DoObserve(const Arrival&) {}
  virtual std::optional<Eigen::Vector3d> DoEstimate(const WindowArrivals& w) = 0;
  virtual std::optional<std::vector<TrackEstimate>> DoTracks() const { return std::nullopt; }

  std::string name_;
  MethodNeeds needs_;
  bool steers_beam_;
};

// `ekf`: the classical baseline fed every pre-processed observation as it
// arrives, asked at the window's end.
std::unique_ptr<LocalizationMethod> MakeEkfMethod(std::unique_ptr<Ekf> ekf);
// `anchor_track`: the anchored head's filter alone on each window's anchors.
std::unique_ptr<LocalizationMethod> MakeAnchorTrackMethod(double window_s);
// `mtt` (`mtt_jpda` with jpda): the multi-target tracker
// (pipeline/multitarget/target_tracker.h) on every detection, associating
// by GNN (JPDA); its Estimate is its oldest confirmed track.
std::unique_ptr<LocalizationMethod> MakeMttMethod(double window_s, bool jpda = false);
// `uavloc_per_track`: the paper's edge network per track of mtt's tracker
// (pipeline/multitarget/per_track_uavloc.h); `make_edge` loads a network.
std::unique_ptr<LocalizationMethod> MakePerTrackMethod(
    double window_s, std::function<std::unique_ptr<EdgeLocalizer>()> make_edge);
// A learned edge network fed the modalities in `modalities` (bit m:
// Modality m); `anchored` when it reads the nodes' geometric anchors.
std::unique_ptr<LocalizationMethod> MakeLearnedMethod(std::string name,
                                                      std::unique_ptr<EdgeLocalizer> edge,
                                                      int modalities, bool anchored);
// A user's TorchScript edge model on every latent that arrived; a failure
// is rethrown as ScriptedEdgeFailure naming the method.
std::unique_ptr<LocalizationMethod> MakeScriptedMethod(std::string name,
                                                       std::unique_ptr<ScriptedEdge> edge);

}  // namespace uavsim::pipeline
