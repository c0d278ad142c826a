// `uavsim reproduce`: the paper's Sec. VI re-run on simulated data, every
// figure and table from one command (apps/reproduce/reproduce_report.h draws them).
//
// The plan is data (ReproducePlan): four episode sets of the same flights
// (same seed, trajectories, weather and loss), which differ only in what
// the nodes pre-process (pre: all; raw: none; raw_camera: LiDAR and radar;
// raw_lidar_radar: the camera), and the trainings ("arms") the artefacts
// need, each a variant (pipeline/variants.h) at a latent size z
// and a training seed, on one set:
//
//   paper      every z: the IB encoders (stage 1; at the scenario's z also
//              the edge network: Figs. 10-15, Tab. IV); split by trajectory,
//              and once more by frame (Fig. 10a's second column)
//   mlp_bottleneck every z, stage 1 only (Figs. 7-9)
//   raw        every z (stage 1; at the scenario's z also stage 2)
//   gru lstm tcn te_align resample_* no_madw no_mica no_madw_mica
//   early_fusion late_fusion modality_dropout hemis: stage 2 on the paper
//              arm's encoders of the same seed (Figs. 11a-14)
//   raw_gru raw_lstm raw_tcn: stage 2 on the raw arm's encoders (Fig. 11b)
//   raw_camera raw_lidar_radar: both stages (Tab. IV)
//
// Every seed s trains on the same episodes (drawn by the plan's data seed)
// with its own split, initial weights and dropout: a seed is a replicate,
// and methods of one seed share their held-out trajectories (paired).
//
// Cached and resumable: DIR/episodes/<set>.eps (extended, never redrawn),
// DIR/models/<arm>/ (appears whole when its training ends; a killed
// reproduction loses only the trainings under way, and the same command
// resumes). Trainings run in child processes, --jobs at a time; under
// mpirun every rank simulates a share of the episodes and rank 0 hands out
// trainings to ranks as sweeps do (other ranks read DIR/episodes, so DIR
// must be on a file system they share).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "apps/reproduce/reproduce_verdict.h"
#include "apps/train/train.h"
#include "pipeline/training_config.h"

namespace uavsim::sim {

struct ReproduceOptions {
  std::string scenario_file;  // a scenario file ("city" and "twin" resolved by the CLI)
  std::string out_dir;        // DIR
  bool quick = false;         // the toy plan (ReproducePlan below)
  int jobs = 1;               // trainings (and episodes) at a time, per rank under mpirun
  bool quiet = false;
  int seeds = 0;             // training seeds (0: the plan's, 3)
  int episodes = 0;          // per set (0: the plan's)
  std::string command_line;  // written into every model's note and the report
  // Another reproduction holds DIR's lock (DIR/.lock, flock'ed while this
  // one runs): wait for it instead of refusing (core::UsageError naming its
  // process).
  bool wait = false;
};

// One training of the plan.
struct ReproduceArm {
  std::string id;       // its folder under DIR/models: "<variant>-z<z>-s<seed>[-frame]"
  std::string variant;  // pipeline::FindVariant name
  int latent_dim = 16;  // z
  std::uint64_t seed = 1;
  std::string set;       // the episode set: EpisodeSetName of the variant's raw modalities
  std::string encoders;  // id of the arm whose stage-1 encoders it reuses ("": trains them)
  bool edge = true;      // trains the paper-layout edge head (false: stage 1 only)
  bool frame_split = false;
};

struct ReproducePlan {
  EpisodePlan episodes;               // of each set (its seed draws the flights)
  pipeline::TrainingConfig training;  // before each variant's keys
  std::vector<int> latent_dims;       // Figs. 7-9, Tab. II
  int scenario_latent_dim = 16;       // the z of the edge-network arms
  int seeds = 3;
  double rate_run_s = 30.0;  // Tab. II: simulated seconds of each data-rate run
  int beam_upa = 32;         // Fig. 15: the base station's array is beam_upa^2
  // The equivalence margin's fraction (apps/reproduce/reproduce_verdict.h), in the
  // plan record before any training.
  double equivalence_fraction = kEquivalenceFraction;
  std::vector<ReproduceArm> arms;  // stage-1 arms before the arms that reuse them
};

// "pre", "raw", "raw_camera", "raw_lidar_radar" for the raw-modality masks
// 0, 7, 1, 6 (bit m: Modality m); "raw<mask>" for any other.
std::string EpisodeSetName(std::uint8_t raw_modalities);

// The plan for a scenario: full (30 episodes of 20 s a set, the default
// training config capped at 6 x 1000 stage-1 observations and 30 stage-2
// epochs, 3 seeds, z in {4, 16, 64}) or quick (every arm at toy size:
// 6 episodes of 5 s, 2 epochs, 2 seeds, z in {4, 16, 64}; for CI and a first
// look). o.seeds and o.episodes override. The scenario's own z is added to
// the latent sizes.
ReproducePlan MakeReproducePlan(const Scenario& base, const ReproduceOptions& o);

struct ReproduceOutcome {
  std::size_t arms = 0;          // in the plan
  std::size_t already_done = 0;  // found trained when the command started
  std::size_t ran = 0;
  std::size_t failed = 0;             // their messages went to stderr; rerun to retry
  bool reported = false;              // the artefacts and report.md/html written
  bool mpi_worker = false;            // a rank other than 0
  double wall_s = 0.0;                // this invocation
  std::vector<std::string> warnings;  // figures not drawn
};

// Runs the plan into o.out_dir. Throws core::UsageError (DIR made by
// another plan, bad options), core::Interrupted on a termination signal
// (finished trainings kept), std::runtime_error for I/O.
ReproduceOutcome RunReproduce(const Scenario& base, const ReproduceOptions& o);

}  // namespace uavsim::sim
