// Edge pipeline parameters: the model file, the alignment window, the IB
// latent size, and which localization methods run (paper Secs. IV-V).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pipeline/baselines/ekf_config.h"
#include "pipeline/node/preprocess_config.h"

namespace uavsim::pipeline {

// A user's edge model run as a method (/pipeline/methods entry
// {"type": "torchscript", "name": NAME, "edge": FILE}): a TorchScript file
// (pipeline/edge/scripted_edge.h says what it is given and must return),
// relative to the scenario's folder. NAME is the method's name in every
// output; it is listed in PipelineConfig::methods like any other.
struct ScriptedMethod {
  std::string name;
  std::string edge;
};

// A method the program embedding the simulator supplies (/pipeline/methods
// entry {"type": "python", "name": NAME, "history_windows": L}): a Python
// function given, at each window's deadline, what a TorchScript method is
// given (the last L windows' latents, pipeline/edge/latent_history.h). The
// scenario names it; `import uavsim` (apps/python) brings the function, and
// a run without it is refused (the command line has none).
struct HostedMethod {
  std::string name;
  int history_windows = 1;
};

struct PipelineConfig {
  std::string model = "default";  // "default": the model shipped for scenarios/default.json
  double window_s = 0.2;          // paper: alignment window t^w = 0.2 s
  int latent_dim = 16;            // paper: z in {4, 8, 16, 32, 64}
  double late_allowance_s = 0.0;  // grace after a window's deadline before a packet counts late
  // uavloc: the paper's pipeline, the fused three-modality estimate; ekf:
  // the classical baseline; uavloc_camera / _lidar / _radar: the same
  // trained network fed only that modality's latents (the paper's
  // single-modality comparison); uavloc_anchored: our anchored head
  // (pipeline/anchored/); anchor_track: its anchor filter alone (no
  // learning). sim/edge_server.h says more.
  std::vector<std::string> methods{"uavloc", "uavloc_anchored", "anchor_track", "ekf"};
  // The entries of `methods` that are a user's TorchScript model (their
  // names are in `methods` too, in the order listed).
  std::vector<ScriptedMethod> scripted;
  // The scripted method named `name`, or null.
  const ScriptedMethod* FindScripted(const std::string& name) const;
  // The entries of `methods` that a host program supplies (Python methods).
  std::vector<HostedMethod> hosted;
  const HostedMethod* FindHosted(const std::string& name) const;
  // uavloc_anchored answers from its first window with a track of its anchor
  // filter (pipeline/edge/edge_localizer.h), as ekf and anchor_track from
  // their first confirmed track; false: from its first window with any data
  // (before a track its range is a guess, metres off). uavloc and the
  // single-modality ablations always answer from their first data.
  bool uavloc_wait_for_track = true;
  PreprocessConfig preprocess;  // the sensing nodes' pre-processing (paper Sec. IV-A)
  EkfConfig ekf;                // the classical baseline
};

// The subset of modalities `bits` allows (bit m: Modality m), 1..7: "all"
// (camera, LiDAR and radar), "camera+lidar", "camera+radar", "lidar+radar",
// "camera", "lidar", "radar" (training reports and method names use them).
// Throws std::invalid_argument outside 1..7.
std::string ModalitySubsetName(int bits);
inline constexpr int kModalitySubsets = 7;

// The fixed method names a scenario may list. Beside them: each variant's
// method (pipeline/variants.h: gru, no_mica, early_fusion, ...),
// and any learned method (uavloc or a variant's) fed a subset of the
// modalities as NAME[SUBSET], SUBSET one of camera, lidar, radar,
// camera+lidar, camera+radar, lidar+radar, all (e.g. uavloc[camera+lidar];
// uavloc_camera is uavloc[camera]).
const std::vector<std::string>& KnownMethods();
// Whether a method that gives several labelled estimates per window (mtt,
// uavloc_per_track) runs.
bool RunsMultiTarget(const PipelineConfig& p);

// A method name taken apart: the learned method it runs ("uavloc", a
// variant's method; empty for anchor_track, ekf and uavloc_anchored) and
// the modalities it is fed (bit m: Modality m; 7 all).
struct MethodName {
  std::string learned;
  int modalities = 7;
};
// nullopt when `name` is not a method a scenario may list (a scripted
// method's name is the scenario's own: PipelineConfig::FindScripted).
std::optional<MethodName> ParseMethod(const std::string& name);

template <class V>
void Visit(V& v, PipelineConfig& c);

}  // namespace uavsim::pipeline
