// `uavsim dataset`: the training simulation's episodes exported to one HDF5
// file for Python users (docs/dataset.md has the schema in full, with units
// and a reading example).
//
// The episodes are exactly `uavsim train`'s (apps/train/train.h): the same plan
// (EpisodePlan: trajectories, seeds, weather and loss drawn per episode from
// --seed), simulated by the same code, `jobs` at a time or on every rank
// under mpirun, or read from (and extended into) an episode file (--data).
// Given a model folder, each frame's IB-CC latent is added: the mean mu its
// node would send, from the model's node encoder (pipeline/node/
// node_encoder.h) on one LibTorch thread, as in the loop.
//
// Schema (apps/dataset/dataset_file.h writes it; world ENU metres, simulated seconds):
//   /                attrs schema_version, uavsim_version, scenario_file,
//                    scenario (resolved JSON), seed, episodes, episode_s,
//                    window_s, latent_dim (0: none), model, modalities, fates
//   /nodes           id, modality, position_m [n,3], rpy_deg [n,3], rate_hz
//   /episodes/NNNNNN attrs index, label, weather, window_s;
//     window_truth_m [K,3]: the target at k t^w, row k - 1
//     frames/  per frame whose pre-processing found something, capture
//              order: t_capture_s, t_arrival_s (NaN: none), fate (0 on
//              time, 1 late, 2 lost, 3 in flight at the end, 255 unknown),
//              on_time, modality, node, window (k: (k-1) t^w <= t < k t^w),
//              truth_m [N,3], latent [N,z] (with a model)
//     camera/  frame (row in frames/), t_observation_s, crop_left/right
//              uint8 [Nc,128,128], detected, centre_*_px [Nc,2], side_*_px,
//              eye_*_m, bearing_*
//     lidar/, radar/  frame, t_observation_s, sensor_position_m,
//              offsets [Np+1], points float32 [P,4|5] (attr channels)
//
// Determinism: the same scenario, seed and options give the same file byte
// for byte, whatever `jobs`, the ranks, or whether the episodes came from
// --data. The file is written atomically: to OUT.tmp-PID beside OUT, then
// renamed; nothing is left under either name on failure or interruption.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "core/modality.h"
#include "sim/scenario.h"

namespace uavsim::sim {

struct DatasetCommand {
  std::string scenario_file;  // for messages and the file's provenance
  std::string out_file;       // the .h5 file
  bool force = false;         // replace an existing out_file
  bool quiet = false;         // no progress, no summary
  std::uint64_t seed = 1;     // the episode plan's seed
  int episodes = 0;           // 0: the plan's default (40)
  double episode_s = 0.0;     // 0: the plan's default (20 s)
  int jobs = 1;               // episodes simulated at a time (per rank under mpirun)
  // A model folder or manifest ("default": the shipped one) whose encoders
  // give each frame's latent; empty: no latents.
  std::string model;
  // An episode file (`uavsim train --data`): read if it exists, extended
  // when it holds fewer episodes than asked, else written after simulating.
  std::string data_file;
};

struct DatasetSummary {
  std::size_t episodes = 0;
  double episode_s = 0.0;
  std::size_t frames[core::kModalityCount] = {};  // per modality
  std::size_t on_time = 0;                        // frames that arrived on time
  std::int64_t latent_dim = 0;                    // 0: no latents
  std::uintmax_t bytes = 0;                       // the file's size
};

// Runs the command. Before anything is simulated or written it refuses,
// with core::UsageError naming the file: an existing out_file without
// `force` (or a folder there), an out folder that cannot be made or written
// to, a model that is missing or broken; with core::ConfigError naming the
// scenario and pointer: a model that does not fit the scenario (latent
// size, window). A failed simulation or write throws std::runtime_error and
// leaves no file. Under mpirun every rank simulates episodes and rank 0
// alone checks and writes; other ranks return nothing.
std::optional<DatasetSummary> RunDatasetExport(const Scenario& base, const DatasetCommand& c);

}  // namespace uavsim::sim
