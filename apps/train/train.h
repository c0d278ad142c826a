// `uavsim train`: training data by simulation and the two-stage training of
// UAVLoc (pipeline/training/trainer.h). Each episode is the scenario with its own
// target trajectory (orbits, figure-eights and random flights around the
// scenario's own flight region), seed, weather (rain, fog) and uplink loss;
// episodes are split 70/15/15 by trajectory (by default) or by frame into
// training, validation and held-out test sets.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/training/dataset.h"
#include "pipeline/training/trainer.h"
#include "pipeline/training_config.h"
#include "pipeline/variants.h"
#include "sim/scenario.h"

namespace boost::mpi {
class communicator;
}

namespace uavsim::sim {

struct EpisodePlan {
  int episodes = 40;         // trajectories
  double episode_s = 20.0;   // simulated seconds each
  std::uint64_t seed = 1;    // draws the variations
  bool vary_weather = true;  // rain and fog draws (below)
  bool vary_loss = true;     // uplink Bernoulli loss draws (below)
  int first_episode = 0;     // index of the first episode (held-out sets use others)
  // The draws of each episode: rain with this probability at a rate uniform
  // in [rain_min_mm_h, rain_max_mm_h], else none; fog with this probability
  // at a visibility uniform in [fog_min_m, fog_max_m], else none; one
  // Bernoulli loss probability uniform in [0, loss_max] for every link.
  double rain_probability = 0.2;
  double rain_min_mm_h = 1.0, rain_max_mm_h = 25.0;
  double fog_probability = 0.1;
  double fog_min_m = 300.0, fog_max_m = 2000.0;
  double loss_max = 0.3;
};

// The scenario of episode i: `base` with the target's trajectory, seed,
// weather and loss drawn from the plan, and, when the target's `episodes`
// lists them (sim/scenario.h), its flight region and size. `label` says
// what was drawn.
Scenario EpisodeScenario(const Scenario& base, const EpisodePlan& plan, int i,
                         std::string* label = nullptr);

// The modalities whose nodes send raw data in `s` (bit m: Modality m): what
// Episode::raw_modalities records.
std::uint8_t RawModalities(const Scenario& s);

// Simulates one episode and collects its samples (no files written).
pipeline::Episode SimulateEpisode(const Scenario& s);

// Episodes first_episode .. first_episode + episodes - 1, in order, in this
// process.
std::vector<pipeline::Episode> SimulateEpisodes(const Scenario& base, const EpisodePlan& plan,
                                                bool quiet);

// Where the episodes are simulated: `jobs` child processes at a time, and
// under mpirun on every rank (apps/sweep/process_farm.h).
struct EpisodeJobs {
  int jobs = 1;
  bool quiet = false;
  std::string scratch_dir;                    // rank 0: where the children write (removed after)
  boost::mpi::communicator* world = nullptr;  // under mpirun, else null
  std::string command = "uavsim train";       // names the command in messages
};
// The same episodes, byte for byte, whatever `jobs` and the ranks. At rank
// 0 (or without MPI) returns them; other ranks return nothing once rank 0
// has all. Throws std::runtime_error if an episode failed.
std::vector<pipeline::Episode> SimulateEpisodes(const Scenario& base, const EpisodePlan& plan,
                                                const EpisodeJobs& jobs);

// `uavsim train --data FILE` when FILE exists: the episodes it holds, cut to
// the first `count` (0: all of them), and the plan of those still to
// simulate when `count` asks for more (`missing.first_episode` = what FILE
// holds, `missing.episodes` = how many more, 0 when none). Episode i depends
// only on the scenario, the seed and i, so the extended set is the one a
// fresh simulation of `count` episodes gives. Throws core::UsageError naming
// FILE (after `command`) when extending a set made with another seed or scenario (an episode's
// label differs from what `plan` draws) or with another episode length
// (`plan.episode_s`, unless `keep_length`: then FILE's length is used).
struct SavedEpisodes {
  std::vector<pipeline::Episode> episodes;
  EpisodePlan missing;
};
SavedEpisodes ReadSavedEpisodes(const Scenario& base, const EpisodePlan& plan, int count,
                                bool keep_length, const std::string& file,
                                const std::string& command = "uavsim train");

// How a command that simulates episodes (`train`, `dataset`) gets them.
struct EpisodeRequest {
  int episodes = 0;          // asked for (0: the plan's); what --data is read to or extended to
  bool keep_length = false;  // --episode-s not given: a --data file's length holds
  std::string data_file;     // --data (empty: none), flock'ed (.FILE.lock) while in use
  int jobs = 1;
  bool quiet = false;
  std::string command = "uavsim train";  // for messages
  // Another command holds the --data file's lock (.FILE.lock beside it):
  // wait for it instead of refusing (core::UsageError naming its process).
  bool wait = false;
};
// The plan's episodes for such a command. Under mpirun (an MPI environment
// held for the call) every rank simulates its share; rank 0 first runs
// `prepare` (the command's own checks and output staging: a throw there
// ends every rank with exit 2 under mpirun, else propagates), reads what
// --data holds, simulates the rest in the folder `scratch()` names and
// extends the --data file. Rank 0 (or without MPI) returns the episodes, with
// `plan.episodes` and `plan.episode_s` set to what they are; other ranks
// return nothing.
std::optional<std::vector<pipeline::Episode>> GatherEpisodes(
    const Scenario& base, EpisodePlan& plan, const EpisodeRequest& request,
    const std::function<void()>& prepare, const std::function<std::string()>& scratch);
// The same inside an MPI environment the caller holds (`world`: its
// communicator; null: no MPI), for commands that gather several episode
// sets (`uavsim reproduce`).
std::optional<std::vector<pipeline::Episode>> GatherEpisodes(
    const Scenario& base, EpisodePlan& plan, const EpisodeRequest& request,
    const std::function<void()>& prepare, const std::function<std::string()>& scratch,
    boost::mpi::communicator* world);

// Splits by trajectory: 15 % test and 15 % validation (at least one each when
// there are three or more episodes), the rest training; which episode goes
// where is a seeded shuffle.
pipeline::Dataset SplitByTrajectory(std::vector<pipeline::Episode> episodes, std::uint64_t seed);
// The part SplitByTrajectory(episodes, seed) puts each of n episodes in:
// 0 training, 1 validation, 2 test (what `uavsim dataset` records, so a
// script can choose on the validation flights `uavsim train --seed` uses).
std::vector<int> TrajectoryParts(std::size_t n, std::uint64_t seed);
// Splits by frame (pipeline::DataSplit::kFrame): each episode goes into every
// part, each of its windows drawn into one part (test with probability 0.15,
// validation 0.15, else training; a seeded draw per window) and scored
// there only. The parts' episodes share the samples by copy (three times the
// memory of the episodes). Throws std::invalid_argument when the draw leaves
// the training or validation part without a window.
pipeline::Dataset SplitByFrame(std::vector<pipeline::Episode> episodes, std::uint64_t seed);

// What --quick changes, in one place: the defaults of the episode plan and of
// the training config, which a config file then overrides. quick = false: the
// plain defaults.
struct TrainDefaults {
  EpisodePlan plan;
  pipeline::TrainingConfig training;
};
// The presets, one home: kFull, the defaults; kQuick, `uavsim train
// --quick`: a small model that learns, in under 3 minutes on 2 cores (the
// tests'); kToy, each training of `uavsim reproduce --quick`: every arm of
// the plan in minutes, numbers that say nothing. The short ones draw no
// weather and take a larger step.
enum class TrainPreset { kFull, kQuick, kToy };
TrainDefaults Defaults(TrainPreset preset);
inline TrainDefaults Defaults(bool quick) {
  return Defaults(quick ? TrainPreset::kQuick : TrainPreset::kFull);
}

// The training config of a command: Defaults(quick).training, then the JSON
// file `config_file` (if not empty), then the "/json/pointer=value"
// overrides (as for scenarios, ApplyOverride). Throws core::ConfigError
// naming the file (or --config-set) and the pointer.
// A variant's keys (`variant`, pipeline/variants.h; null: none) go
// between the defaults and the file.
pipeline::TrainingConfig ResolveTrainingConfig(bool quick, const std::string& config_file,
                                               const std::vector<std::string>& overrides = {},
                                               const pipeline::Variant* variant = nullptr);

struct TrainCommand {
  std::string scenario_file;
  std::string out_dir;  // the model folder
  bool force = false;
  bool quick = false;  // Defaults(true).plan (and `training` resolved with quick)
  bool quiet = false;
  std::uint64_t seed = 1;  // the split, the initial weights, dropout
  // The seed that draws the episodes (EpisodePlan::seed); unset: `seed`.
  // Several training seeds on one episode file (`uavsim reproduce`).
  std::optional<std::uint64_t> data_seed;
  int episodes = 0;             // 0: the plan's default
  double episode_s = 0.0;       // 0: the plan's default
  bool mlp_bottleneck = false;  // the paper's MLP baseline instead of the IB head
  // The variant trained (pipeline/variants.h): recorded in the
  // model, its method named in the report. Its training keys are already in
  // `training`, its node-side choices in mlp_bottleneck and the scenario.
  std::string variant = "paper";
  // A model folder whose stage-1 encoders to reuse (stage 2 only); empty:
  // train them. Must be a model of the same scenario and latent size whose
  // variant's nodes send what this variant's do (pipeline::SameNodes: e.g.
  // paper for gru, raw for raw_gru); core::UsageError naming it else.
  std::string encoders_dir;
  bool score_classical = true;  // the classical methods in the report (replays the test episodes)
  bool paper_head = true;       // train the paper's linear edge head (uavloc)
  bool anchored_head = true;    // train our anchored edge head (uavloc_anchored)
  pipeline::DataSplit split = pipeline::DataSplit::kTrajectory;
  // Train on the first N episodes of the training part only (0: all); the
  // validation and test parts stay whole (learning curves on one test set).
  int train_episodes = 0;
  pipeline::TrainingConfig training;  // as ResolveTrainingConfig gives it
  int threads = 1;                    // LibTorch intra-op threads (see NOTES.md: 1 is fastest here)
  int jobs = 1;                       // episodes simulated at a time (per rank under mpirun)
  // Episode file: read if it exists (no simulation), else written after
  // simulating. Empty: simulate, keep nothing. Locked while in use
  // (EpisodeRequest::wait).
  std::string data_file;
  bool wait = false;         // --wait: for another command's lock on data_file
  std::string command_line;  // written into the model's note
};

// Runs the whole command: simulate, train, write the model folder
// atomically. Returns the report; under mpirun, ranks other than 0 only
// simulate episodes and return nothing.
std::optional<pipeline::TrainReport> RunTraining(const Scenario& base, const TrainCommand& c);

// The training part of RunTraining on episodes already at hand (drawn by
// `plan`, which the model's note states): split, train, write the model
// folder c.out_dir atomically. c.episodes, episode_s, jobs and data_file
// are not used. Call pipeline::InitTorch first (it is called again with
// c.seed before training).
pipeline::TrainReport TrainOnEpisodes(const Scenario& base, const TrainCommand& c,
                                      std::vector<pipeline::Episode> episodes,
                                      const EpisodePlan& plan);

// The variant's node-side choices applied to a scenario: its raw modalities'
// nodes encode raw data (/pipeline/preprocess/<modality>/raw).
void ApplyVariantNodes(const pipeline::Variant& v, Scenario& s);

}  // namespace uavsim::sim
