// The edge server as the run wires it (DESIGN.md: channel/uplink ->
// pipeline/edge): it accounts for every message the nodes send (delivered,
// late, lost: channel/edge_receiver.h), hands what arrives on time to each
// localization method, and at each alignment window's deadline asks every
// method for its estimate of the target at the window's end.
//
// Methods (/pipeline/methods), every one scored on the same windows, each
// a pipeline::LocalizationMethod (pipeline/localization_method.h) in one
// list: ekf (the classical baseline), uavloc (the paper's pipeline),
// uavloc_camera/_lidar/_radar and NAME[SUBSET] (it or a variant fed a subset
// of the modalities), the paper's variants (gru, no_mica, ...),
// uavloc_anchored (our anchored head), anchor_track (its filter alone),
// mtt (the multi-target tracker) and users' TorchScript models; pipeline/model_catalog.h resolves
// the learned and TorchScript ones to their model folders, once per run. The nodes send their
// geometric anchors with their latents only when uavloc_anchored or anchor_track runs (MessageBytes
// counts them).
//
// Determinism: no randomness of its own; LibTorch is seeded from the
// scenario's seed when a model is loaded.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "channel/edge_receiver.h"
#include "channel/packet.h"
#include "core/json_io.h"
#include "core/wall_profile.h"
#include "pipeline/baselines/ekf.h"
#include "pipeline/localization_method.h"
#include "pipeline/model_catalog.h"
#include "pipeline/node/node_encoder.h"
#include "sim/hosted_method.h"
#include "sim/model_check.h"
#include "sim/scenario.h"
#include "sim/sensing_node.h"

namespace uavsim::sim {

// What `validate` checks of that model: the manifest exists and parses,
// the folder's checksums hold, it has the edge head each method needs, and
// its latent size and window length are the scenario's (the rules the run
// applies when it loads the model); the TorchScript methods load. No
// weights are loaded when the folders (the model's and its variants') have
// checksums.sha256; a folder without one is loaded as the run loads it,
// with a warning on stderr unless `quiet`. Nothing when no method needs a
// model. Throws core::ConfigError naming `file` and the scenario's pointer
// (or the model's file that does not load), or a Python method without its
// function in `hosted` (sim/hosted_method.h).
void CheckTrainedModel(const Scenario& s, const std::string& file, bool quiet = false,
                       const HostedMethods* hosted = nullptr);

// A model folder (or its manifest; "default": the shipped model) whose node
// encoders a command runs on the scenario's observations outside the loop
// (`uavsim dataset --model DIR`): what CheckTrainedModel checks of
// /pipeline/model that concerns the encoders. The manifest exists and
// parses, the folder's checksums hold, its latent size and window length are
// the scenario's, and a raw-variant model meets raw pre-processing. Returns
// the manifest's path. Throws core::UsageError "COMMAND: --model DIR: ..."
// for a missing or broken model, core::ConfigError naming `file` and the
// scenario's pointer for one that does not fit.
std::string CheckEncoderModel(const Scenario& s, const std::string& file, const std::string& dir,
                              const std::string& command);

// What identifies the IB-CC encoders the scenario's nodes run, for the
// sensing key (sim/sensing_trace.h): "none" when no method needs a model,
// else SHA-256 over the model folder's files (names and contents). Loads no
// weights. Throws core::ConfigError as CheckTrainedModel for a model that
// does not resolve.
std::string EncoderFingerprint(const Scenario& s, const std::string& file);

// The `ekf` method as a run builds it: the scenario's EkfConfig with the
// target's limits and size, every node's sensor added under its id.
std::unique_ptr<pipeline::Ekf> MakeEkf(const Scenario& s);

class EdgeServer {
 public:
  // Builds the scenario's methods. With `methods` false (training-data
  // collection) no method runs and no model is loaded: the server only
  // accounts. Throws core::ConfigError naming `scenario_file` and
  // /pipeline/model (or /pipeline/latent_dim, /pipeline/window_s) when the
  // model is missing or does not fit the scenario; warns on stderr (unless
  // quiet) when it was trained for another world or node layout. `hosted`:
  // the Python methods' factories (null: none; a scenario that lists one
  // without its factory is a ConfigError).
  EdgeServer(const Scenario& scenario, const std::string& scenario_file, bool quiet, bool methods,
             const HostedMethods* hosted = nullptr);
  ~EdgeServer();

  // The uplinks' side (the nodes report what they send to receiver()
  // directly). OnArrival feeds the methods and returns whether the
  // message arrived on time with content (late ones count as missing).
  bool OnArrival(const channel::Message& m, core::SimTime t_arrival);
  void OnLost(const channel::Message& m) { receiver_.OnLost(m); }

  // At the deadline of window k = tick + 1, whose end is t_s: each method's
  // estimate of the target (world ENU, metres), absent where it has none yet.
  std::map<std::string, Eigen::Vector3d> EstimateWindow(std::int64_t tick, double t_s);

  // The multi-target methods' labelled estimates of the window
  // EstimateWindow last estimated (sim/window_scorer.h scores them as sets).
  const std::map<std::string, std::vector<pipeline::TrackEstimate>>& last_tracks() const {
    return last_tracks_;
  }

  // What reached the edge on time, kept per window for a host that steps
  // the run (apps/python's environment): off by default.
  struct ArrivalRecord {
    std::string node_id;
    core::Modality modality = core::Modality::kCamera;
    double t_capture_s = 0.0;
    std::vector<float> latent;         // empty without a model
    pipeline::GeometricAnchor anchor;  // the node's detection (kNone: nothing found)
  };
  void set_keep_arrivals(bool keep) { keep_arrivals_ = keep; }
  // The arrivals of the window EstimateWindow last estimated, in arrival order.
  const std::vector<ArrivalRecord>& last_arrivals() const { return last_arrivals_; }

  channel::EdgeReceiver& receiver() { return receiver_; }
  const channel::EdgeReceiver& receiver() const { return receiver_; }
  // The IB-CC encoder the nodes of modality m run (null without a model).
  const pipeline::NodeEncoder* encoder(core::Modality m) const;
  // Bytes of a node's message that carries something: the latent and its
  // header, plus the geometric anchor when uavloc_anchored or anchor_track
  // runs.
  std::uint32_t MessageBytes(core::Modality m) const;
  // The methods whose estimates steer a beam (the single-modality
  // ablations steer none), in the order the downlink scores them.
  std::vector<std::string> SteeredMethods() const;
  // metrics.json's "uavloc_model" (path, trained_for, same_layout, heads:
  // the edge heads the model holds, "paper" and/or "anchored"); null
  // without a model.
  const core::Json& model_info() const;
  // EncoderFingerprint of the scenario this server runs ("none" without
  // methods).
  std::string encoder_fingerprint() const;

  // Times each method into `profile` ("edge/<method>"); null: no timing.
  void set_profile(core::WallProfile* profile) { profile_ = profile; }

 private:
  const Scenario& scenario_;
  channel::EdgeReceiver receiver_;
  core::SimTime window_ns_;
  std::unique_ptr<pipeline::ModelCatalog> catalog_;  // null when no method runs
  // In the order the downlink scores them (SteeredMethods).
  std::vector<std::unique_ptr<pipeline::LocalizationMethod>> methods_;
  pipeline::MethodNeeds needs_;                               // what any of them needs
  std::map<std::int64_t, pipeline::WindowArrivals> pending_;  // window k -> what arrived
  bool keep_arrivals_ = false;
  std::map<std::int64_t, std::vector<ArrivalRecord>> pending_records_;
  std::vector<ArrivalRecord> last_arrivals_;
  std::map<std::string, std::vector<pipeline::TrackEstimate>> last_tracks_;
  // Every observation of the message into window k's detections.
  void AddDetections(std::int64_t k, const channel::Message& m, const NodeContent& content);
  core::WallProfile* profile_ = nullptr;
};

}  // namespace uavsim::sim
