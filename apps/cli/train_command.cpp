// `uavsim train` as typed: its usage, options and help (its body:
// apps/cli/train.cpp; the command table: cli.h).
#include <cstdio>
#include <map>
#include <string>

#include "apps/cli/cli.h"
#include "core/error.h"
#include "pipeline/variants.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

const char* kHelp =
    "usage: uavsim train SCENARIO.json [--out MODEL] [--config TRAIN.json]\n"
    "                    [--config-set /ptr=value]... [--quick] [--seed N] [--episodes N]\n"
    "                    [--episode-s S] [--data-seed N] [--bottleneck ib|mlp] [--head H]\n"
    "                    [--threads N]"
    " [--jobs N] [--data FILE] [--split trajectory|frame]\n"
    "                    [--train-episodes N] [--set /ptr=value]... [--force] [--quiet]\n"
    "       mpirun -np K uavsim train SCENARIO.json ... (every rank simulates episodes)\n"
    "\n"
    "Generates training data by simulation and trains the UAVLoc model with LibTorch on\n"
    "the CPU. Each episode is the scenario with its own target trajectory (orbit,\n"
    "figure-eight or random flight around the scenario's flight region), seed, weather\n"
    "and uplink loss; episodes are split 70/15/15 (--split). Stage 1 trains each\n"
    "modality's IB-CC encoder, stage 2 TE-Align, MADW, MICA and Mamba on the sequences of\n"
    "latents that arrived in time, with random modality dropout, once per edge head (the\n"
    "paper's for uavloc, ours for uavloc_anchored). Adam, early stopping on validation.\n"
    "The model folder MODEL (default models/NAME) gets model.json (with the resolved\n"
    "training config under \"training\"), the parts and training_report.json (losses and\n"
    "held-out RMSE per head); use it with --set /pipeline/model=MODEL or\n"
    "\"pipeline\": {\"model\": \"MODEL\"}.\n"
    "\n"
    "  --config F     the training config, a JSON object; every key has a default ({} is\n"
    "                 valid); scenarios/training/default.json spells out all of them and\n"
    "                 scenarios/training/README.md says what each does:\n"
    "                 dropout beta stage1_lr stage1_batch stage1_max_epochs stage1_patience\n"
    "                 stage1_plateau_epochs\n"
    "                 stage1_min_samples_per_epoch stage1_max_samples_per_epoch\n"
    "                 stage1_max_validation_samples stage1_label_gate_m\n"
    "                 stage1_label_gate_deg stage2_lr stage2_batch stage2_sequence_windows\n"
    "                 stage2_max_epochs stage2_patience stage2_plateau_epochs\n"
    "                 stage2_min_steps_per_epoch modality_dropout window_dropout d_model\n"
    "                 layers temporal (mamba|gru|lstm|tcn) mica_lambda_init\n"
    "                 te_align_tau_origin (window|clock)\n"
    "                 camera_stereo_branches (shared|two)\n"
    "                 camera_eye_pool_side camera_roi_geometry\n"
    "                 point_frame (scene|centroid) point_norm (batch|group|none)\n"
    "                 ib_mse_units (metres|normalised)\n"
    "                 selection_weight\n"
    "                 selection_radius_m filter_preference_m offset_calibration_radius_m\n"
    "                 position_loss (mixture|mean) alignment (te_align|first|middle|random)\n"
    "                 madw mica fusion (uavloc|early|late|hemis);\n"
    "                 scenarios/training/paper.json is the\n"
    "                 paper's preset (learning rate 1e-4, its camera encoder)\n"
    "  --config-set P=V  override the training config's value at JSON pointer P\n"
    "  --quick        a small model in under 3 minutes (17 dry episodes of 10 s; fewer\n"
    "                 epochs and a larger step as config defaults, which --config overrides)\n"
    "  --episodes N   trajectories to simulate (default 40, at least 3)\n"
    "  --episode-s S  simulated seconds each (default 20)\n"
    "  --seed N       seeds the episodes, the split and the weights (default 1)\n"
    "  --data-seed N  seeds the episodes instead (default: --seed): several training\n"
    "                 seeds on one --data file\n"
    "  --bottleneck B ib (default: the paper's IB-CC head, mu/sigma and KL) or mlp (its\n"
    "                 MLP baseline of equal depth and parameter count, no KL): the same as\n"
    "                 --variant mlp_bottleneck\n"
    "  --head H       the edge heads to train on the same encoders: both (default), paper\n"
    "                 (the paper's linear head: method uavloc) or anchored (ours: the Mamba\n"
    "                 output picks among the nodes' geometric anchors; uavloc_anchored)\n"
    "                 or none (stage 1 only: the encoders and their decoders' held-out\n"
    "                 scores, a model no method can run)\n"
    "  --split S      trajectory (default: each episode in one of training, validation,\n"
    "                 test) or frame (the random frame split common in the literature:\n"
    "                 every episode's windows drawn 70/15/15 into the three parts, each\n"
    "                 scored in its part only; neighbouring windows share a flight)\n"
    "  --train-episodes N  train on the first N episodes of the training part only;\n"
    "                 validation and test stay whole (learning curves on one test set)\n"
    "  --threads N    LibTorch threads (default 1); results depend on it\n"
    "  --jobs N       episodes simulated at a time, each in its own process with cores / N\n"
    "                 threads (default 1; per rank under mpirun, where rank 0 hands out\n"
    "                 episodes and trains); the episodes are the same whatever N\n"
    "  --data FILE    the simulated episodes: read FILE if it exists (no simulation),\n"
    "                 else simulate and write it (train again without simulating);\n"
    "                 with --episodes N, the first N of FILE, and when FILE holds fewer\n"
    "                 (made with the same scenario and seed) the missing ones are\n"
    "                 simulated and FILE extended: the same set as a fresh simulation\n"
    "  --wait         when another command uses FILE (its lock .FILE.lock beside it),\n"
    "                 wait for it instead of refusing (exit 2, naming its process)\n"
    "  --variant V    a baseline or ablation of the paper's Sec. VI (list below): its\n"
    "                 training keys apply before --config; the model (default folder\n"
    "                 models/NAME-V) runs in the loop as method V (paper: uavloc)\n"
    "  --encoders DIR reuse the stage-1 encoders of the model DIR (same scenario and latent\n"
    "                 size, a variant whose nodes send the same: paper's for gru, raw's for\n"
    "                 raw_gru): only stage 2 is trained\n"
    "  --set P=V      override the scenario's value at JSON pointer P\n"
    "  --force        replace an existing MODEL folder\n"
    "\n"
    "--lr, --selection-weight, --filter-preference, --offset-calibration, --plateau,\n"
    "--position-loss and --label-gate were replaced by training config keys (issue 17).\n";

// The variants' section of `uavsim train --help`, from the list itself.
std::string TrainVariantsHelp() {
  std::string out =
      "\nvariants (--variant; the paper's Sec. VI; each runs in the loop as a method):\n";
  for (const pipeline::Variant& v : pipeline::Variants()) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-16s %s (%s)\n", v.name, v.description, v.figure);
    out += line;
  }
  return out;
}

// Tuning flags that the training config replaced (issue 17): flag -> its keys.
const std::map<std::string, std::string>& ReplacedTrainFlags() {
  static const std::map<std::string, std::string> replaced{
      {"--lr", "stage1_lr and stage2_lr"},
      {"--selection-weight", "selection_weight"},
      {"--filter-preference", "filter_preference_m"},
      {"--offset-calibration", "offset_calibration_radius_m"},
      {"--plateau", "stage2_plateau_epochs"},
      {"--position-loss", "position_loss"},
      {"--label-gate", "stage1_label_gate_m and stage1_label_gate_deg"},
  };
  return replaced;
}

// A flag the training config replaced is refused by name, also when it is
// the last argument (where parsing would first ask for its value).
void RefuseReplaced(const std::string& flag) {
  const auto it = ReplacedTrainFlags().find(flag);
  if (it == ReplacedTrainFlags().end()) return;
  const std::string& keys = it->second;
  throw UsageError("uavsim train: " + flag + " was replaced by the training config key" +
                   (keys.find(" and ") == std::string::npos ? " " : "s ") + keys +
                   " (--config FILE or --config-set /" + keys.substr(0, keys.find(' ')) +
                   "=VALUE; see uavsim train --help)");
}

void RefuseReplacedLast(int argc, char** argv) {
  if (argc > 2) RefuseReplaced(argv[argc - 1]);
}

std::string Help() { return kHelp + TrainVariantsHelp(); }

std::vector<Option> TrainOptions() {
  std::vector<Option> options;
  for (const char* name : {"--out", "--seed", "--episodes", "--episode-s", "--threads", "--jobs",
                           "--set", "--data", "--bottleneck", "--head", "--config", "--config-set",
                           "--split", "--train-episodes", "--variant", "--encoders", "--data-seed"})
    options.push_back({name, true});
  // Taking a value, so that they are refused by name (RefuseReplaced).
  for (const auto& [flag, keys] : ReplacedTrainFlags()) options.push_back({flag, true});
  for (const char* name : {"--quick", "--force", "--wait"}) options.push_back({name, false});
  return options;
}

}  // namespace

void RefuseReplacedTrainFlags(const ParsedArgs& a) {
  for (const auto& [flag, keys] : ReplacedTrainFlags())
    if (a.Has(flag)) RefuseReplaced(flag);
}

Command TrainCommand() {
  return {"train",
          "train SCENARIO.json",
          "train the UAVLoc model by simulation",
          TrainOptions(),
          Help,
          RunTrainCommand,
          RefuseReplacedLast};
}

}  // namespace uavsim::cli
