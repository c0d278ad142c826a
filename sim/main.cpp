// The uavsim command line (DESIGN.md "Command line"). Errors from bad input
// are caught here once: one line on stderr, exit code 2.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/edge/scripted_edge.h"
#include "results/run_report.h"
#include "sim/bench_beam.h"
#include "sim/bench_events.h"
#include "sim/bench_flops.h"
#include "sim/bench_link.h"
#include "sim/bench_noise.h"
#include "sim/bench_pipeline.h"
#include "sim/bench_radar.h"
#include "sim/bench_raycast.h"
#include "sim/core/error.h"
#include "sim/dataset_export.h"
#include "sim/edge_server.h"
#include "sim/reproduce.h"
#include "sim/reproduce_report.h"
#include "sim/run.h"
#include "sim/run_cost.h"
#include "sim/scenario.h"
#include "sim/sweep.h"
#include "sim/sweep_spec.h"
#include "sim/train.h"
#include "sim/version.h"

namespace {

using uavsim::core::UsageError;

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;

// --verbose: a failing TorchScript method's whole traceback after its line.
bool g_verbose = false;

const char* kMainHelp =
    "uavsim: discrete-event network and sensing simulator for edge-assisted multimodal UAV "
    "localization\n"
    "\n"
    "usage: uavsim COMMAND [OPTIONS]\n"
    "\n"
    "commands:\n"
    "  validate SCENARIO.json     check a scenario; exit 0, or exit 2 with FILE: /json/pointer: "
    "message\n"
    "  run SCENARIO.json          run a scenario and write its run directory\n"
    "  sweep SPEC.json            run a grid of scenarios (packet loss x weather x seeds)\n"
    "  train SCENARIO.json        train the UAVLoc model by simulation\n"
    "  dataset SCENARIO.json      export the training simulation's episodes to HDF5\n"
    "  reproduce [--scenario S]   the paper's Sec. VI: every figure and table, with verdicts\n"
    "  report DIR                 redraw a run's or a sweep's report.html from its files\n"
    "  bench [raycast|radar|events|link|beam|pipeline|noise|flops|all]   measure the hot paths\n"
    "\n"
    "options: --help (also after a command), --version, --quiet (every command)\n"
    "exit codes: 0 ok, 1 failure while running, 2 bad input or usage, 130 interrupted\n";

const char* kValidateHelp =
    "usage: uavsim validate SCENARIO.json [MORE.json]... [--set /json/pointer=value]...\n"
    "                       [--record camera,lidar,radar,mcap] [--resolved] [--quiet]\n"
    "\n"
    "Checks each SCENARIO.json strictly (unknown keys, types, ranges, references, files,\n"
    "meshes, the trained model's manifest and checksums, resource limits: rays and\n"
    "memory against this machine's). Exit 0 if all are valid, else exit 2 with one line\n"
    "on stderr per invalid file:\n"
    "  FILE: /json/pointer: expected ..., got ...\n"
    "\n"
    "  --set P=V     override the value at JSON pointer P (V is JSON, or a bare string),\n"
    "                in every file\n"
    "  --resolved    print the scenario with every default filled, as JSON, on stdout\n"
    "                (one file only)\n"
    "  --record LIST also say how many bytes `run --record LIST` would write at most\n"
    "  --quiet       print nothing on success\n";

const char* kRunHelp =
    "usage: uavsim run SCENARIO.json [--out DIR] [--seed N] [--duration S] [--record "
    "camera,lidar,radar,mcap]\n"
    "                               [--set /json/pointer=value]... [--force] [--quiet] "
    "[--verbose]\n"
    "\n"
    "Runs the scenario and writes DIR (default runs/NAME-sSEED): manifest.json, truth.csv,\n"
    "estimates.csv, metrics.json (RMSE per method, packets, data rates), packets.csv,\n"
    "rate_snr.csv/.png, world_top.csv and layout.csv (the map), report.html (figures and\n"
    "tables: open it in a browser) with report/, and recorded frames. The directory\n"
    "appears only when the run is complete. Methods (/pipeline/methods): uavloc (the\n"
    "paper's pipeline), uavloc_camera/_lidar/_radar (it on one modality), uavloc_anchored\n"
    "(our anchored head), anchor_track (its filter alone), ekf (the classical baseline).\n"
    "The learned ones use the model /pipeline/model names (\"default\": the one shipped\n"
    "for scenarios/default.json; `uavsim train` makes others).\n"
    "\n"
    "  --out DIR       run directory (refused if it exists, unless --force)\n"
    "  --seed N        override the scenario's seed (same as --set /seed=N)\n"
    "  --duration S    override duration_s (same as --set /duration_s=S)\n"
    "  --record LIST   record raw frames of these modalities under DIR/frames/; mcap:\n"
    "                  DIR/recording.mcap, every sensor, the world, truth, estimates and\n"
    "                  uplink in one file for Foxglove (docs/recordings.md)\n"
    "  --set P=V       override the value at JSON pointer P\n"
    "  --force         replace DIR if it exists\n"
    "  --quiet         no progress or summary output\n"
    "  --verbose       a failing TorchScript method's whole traceback after its line\n";

const char* kReportHelp =
    "usage: uavsim report DIR [--quiet]\n"
    "\n"
    "Redraws the report of a run directory (report.html, report/, rate_snr.png) or of a\n"
    "finished sweep folder (summary.csv, aggregate.csv, plots/, report.html) from the\n"
    "files already there, without simulating anything: after a change of style, or for a\n"
    "directory made by an older uavsim (figures whose input file it lacks say so).\n"
    "For a folder of uavsim reproduce (claims.csv, the artefact CSVs, report.md: what\n"
    "docs/paper keeps) it redraws the verdicts from claims.csv with this binary's rules,\n"
    "training nothing: claims.csv and the verdict sections of report.md/report.html.\n"
    "Open DIR/report.html in a browser; it needs no network access.\n"
    "\n"
    "  --quiet   print nothing on success (warnings about figures not drawn still go to\n"
    "            stderr)\n"
    "exit codes: 0 written, 2 DIR is neither a run directory, a finished sweep nor a\n"
    "reproduction, or one of its files is malformed\n";

const char* kSweepHelp =
    "usage: uavsim sweep SPEC.json [--out DIR] [--jobs N] [--shard I/N] [--wait] [--quiet]\n"
    "       uavsim sweep merge DIR [--quiet]\n"
    "       mpirun -np K uavsim sweep SPEC.json [--out DIR] [--jobs N]\n"
    "\n"
    "Runs the Cartesian grid of scenario variations in SPEC.json (parameters as JSON\n"
    "pointers into a base scenario with lists, ranges or named cases of values, times\n"
    "the seeds), each point a run directory DIR/points/<id>/ (default DIR: runs/NAME).\n"
    "Every point is checked before anything runs. Rerunning the same command resumes:\n"
    "finished points are kept, killed ones redone. When all points are done, DIR gets\n"
    "summary.csv (a row per point), aggregate.csv (mean and 95 % confidence interval over\n"
    "the seeds), plots/ (RMSE, coverage and delivery vs each numeric parameter as small\n"
    "multiples with confidence bands, rate vs SNR per setting) and report.html, which\n"
    "shows them (`uavsim report DIR` redraws it). The spec format is in\n"
    "scenarios/sweeps/README.md.\n"
    "\n"
    "  --out DIR     the sweep folder (default runs/NAME)\n"
    "  --jobs N      points at a time (default 1; each gets cores / N threads); under\n"
    "                mpirun, per rank: rank 0 hands points to ranks as they free up\n"
    "  --shard I/N   run only the points whose index is I modulo N (0 <= I < N), e.g. a\n"
    "                Slurm array task; then `uavsim sweep merge DIR` writes the tables\n"
    "  --wait        when another sweep runs in DIR (its lock DIR/.lock), wait for it\n"
    "                instead of refusing (exit 2, naming its process)\n"
    "  --quiet       no progress or summary output\n"
    "exit codes: 0 all points done, 1 some points failed (rerun to retry them), 2 bad\n"
    "input, 130 interrupted (finished points are kept)\n";

const char* kTrainHelp =
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

const char* kDatasetHelp =
    "usage: uavsim dataset SCENARIO.json --out FILE.h5 [--episodes N] [--episode-s S]\n"
    "                      [--seed N] [--jobs N] [--model DIR] [--data FILE]\n"
    "                      [--set /ptr=value]... [--force] [--quiet]\n"
    "       mpirun -np K uavsim dataset SCENARIO.json --out FILE.h5 ... (every rank simulates)\n"
    "\n"
    "Simulates the episodes `uavsim train` would (the same flights, weather and uplink loss\n"
    "drawn from --seed, byte for byte) and writes them to one HDF5 file for Python (h5py,\n"
    "PyTorch): per episode the target's position at each window's end; per frame of each\n"
    "node whose pre-processing found something its capture and arrival times, its fate on\n"
    "the uplink (on time, late, lost, in flight), modality, node, window, the target's\n"
    "position, and the pre-processed content (the camera's two 128 x 128 ROI crops and\n"
    "their geometry; LiDAR and radar point clusters with their channels); with --model each\n"
    "frame's IB-CC latent; the resolved scenario, seed and version as attributes. The\n"
    "schema, units and a reading example are in docs/dataset.md. The same command gives\n"
    "the same file byte for byte, whatever --jobs; the file appears only when complete.\n"
    "\n"
    "  --out FILE.h5  the file to write (required; refused if it exists, unless --force)\n"
    "  --episodes N   trajectories to simulate (default 40)\n"
    "  --episode-s S  simulated seconds each (default 20)\n"
    "  --seed N       seeds the episodes (default 1)\n"
    "  --jobs N       episodes simulated at a time, each in its own process (default 1;\n"
    "                 per rank under mpirun, where rank 0 hands out episodes and writes)\n"
    "  --model DIR    a model folder as `uavsim train` writes it (\"default\": the shipped\n"
    "                 one): add each frame's latent, the mean its node's IB-CC encoder\n"
    "                 sends; the model must fit the scenario (latent size, window)\n"
    "  --data FILE    an episode file as `uavsim train --data` keeps it: read FILE if it\n"
    "                 exists (no simulation; extended when it holds fewer than --episodes),\n"
    "                 else simulate and write it too\n"
    "  --set P=V      override the scenario's value at JSON pointer P\n"
    "  --force        replace an existing FILE.h5\n"
    "  --quiet        no progress or summary output\n"
    "exit codes: 0 written, 1 failure while running (nothing written), 2 bad input or usage\n"
    "(nothing written), 130 interrupted\n";

// The variants' section of `uavsim train --help`, from the list itself.
std::string TrainVariantsHelp() {
  std::string out =
      "\nvariants (--variant; the paper's Sec. VI; each runs in the loop as a method):\n";
  for (const uavsim::pipeline::Variant& v : uavsim::pipeline::Variants()) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-16s %s (%s)\n", v.name, v.description, v.figure);
    out += line;
  }
  return out;
}

const char* kReproduceHelp =
    "usage: uavsim reproduce [--scenario S] [--quick] [--jobs N] [--out DIR] [--seeds K]\n"
    "                        [--episodes N] [--set /ptr=value]... [--wait] [--quiet]\n"
    "       mpirun -np K uavsim reproduce ... (ranks share the episodes and the trainings)\n"
    "\n"
    "Re-runs the evaluation of the paper's Sec. VI on simulated data: simulates four\n"
    "episode sets of the same flights (nodes pre-processing all, none, LiDAR and radar\n"
    "only, the camera only), trains every variant the figures need (uavsim train\n"
    "--variant) at every latent size and training seed, scores them on held-out\n"
    "trajectories, and writes one CSV and one PNG per artefact (Figs. 7-15, Tables II-IV),\n"
    "claims.csv, report.md and report.html: each result beside the paper's claim with a\n"
    "verdict (holds / does not hold / not resolved / mixed) from intervals over seeds, and\n"
    "for each comparison not resolved the seeds it would need (--seeds K trains that many;\n"
    "the seeds already trained in DIR are kept). uavsim report DIR redraws the verdicts\n"
    "from claims.csv alone.\n"
    "Cached and resumable: DIR/episodes/*.eps and DIR/models/<training>/ are kept; a killed\n"
    "reproduction loses only the trainings under way and the same command resumes.\n"
    "\n"
    "  --scenario S   city (default: scenarios/default.json), twin (scenarios/mmaud_twin.json)\n"
    "                 or a scenario file\n"
    "  --quick        every artefact at toy size (6 episodes of 5 s, 2 epochs, 2 seeds, z 4,\n"
    "                 16, 64): minutes, for a first look and CI; its numbers say nothing\n"
    "                 about the paper\n"
    "  --jobs N       trainings (and episodes) at a time, each in its own process with one\n"
    "                 LibTorch thread (default 1; per rank under mpirun)\n"
    "  --out DIR      default runs/reproduce-NAME (-quick with --quick)\n"
    "  --seeds K      training seeds (default 3; quick 2); on an existing DIR only the\n"
    "                 seeds it lacks are trained\n"
    "  --episodes N   flights per episode set (default 60; quick 6)\n"
    "  --set P=V      override the scenario's value at JSON pointer P\n"
    "  --wait         when another reproduction runs in DIR (its lock DIR/.lock), wait for\n"
    "                 it instead of refusing (exit 2, naming its process)\n"
    "\n"
    "exit codes: 0 reported, 1 some trainings failed (rerun to retry them), 2 bad input,\n"
    "130 interrupted (finished trainings are kept)\n";

const char* kBenchHelp =
    "usage: uavsim bench [raycast|radar|events|link|beam|pipeline|noise|flops|all] [--quiet]\n"
    "\n"
    "  raycast    Embree rtcIntersect1 throughput vs each sensor's rays per second in the\n"
    "             default city; the camera's packet speed-up; camera + LiDAR real-time factor\n"
    "  radar      FMCW radar frame: scatterers (with the static cache and without), IF-cube\n"
    "             synthesis, processing (one thread)\n"
    "  events     the event core: hold model (pop earliest, schedule one at a random delay)\n"
    "             with 1e3..1e6 pending events; events per second\n"
    "  link       messages per second through one uplink under the event core\n"
    "  beam       downlink beam evaluations per second (channel, steering, gain)\n"
    "  pipeline   IB-CC encode per frame (camera, LiDAR, radar) and edge inference per\n"
    "             window, one thread\n"
    "  noise      standard normals per second: counter-based Ziggurat vs RngStream::Normal\n"
    "  flops      the paper's Table III: MFLOPs per frame of each encoder (counted from the\n"
    "             layers' shapes, 2 FLOPs per multiply-add as in the paper) and of each\n"
    "             pre-processing step (an estimate from the algorithms' operation counts),\n"
    "             beside the paper's values; no timing\n"
    "  all        everything available (default)\n";

// Flags of one command: name -> takes a value.
struct ParsedArgs {
  std::vector<std::string> positional;
  std::map<std::string, std::vector<std::string>> values;
  std::set<std::string> flags;
  bool Has(const std::string& f) const { return flags.count(f) || values.count(f); }
  std::optional<std::string> Value(const std::string& f) const {
    auto it = values.find(f);
    if (it == values.end()) return std::nullopt;
    return it->second.back();
  }
};

ParsedArgs Parse(const std::string& cmd, int argc, char** argv, int first,
                 const std::set<std::string>& value_options,
                 const std::set<std::string>& flag_options) {
  ParsedArgs a;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
      std::string name = arg, value;
      bool has_inline = false;
      if (auto eq = arg.find('='); eq != std::string::npos) {
        name = arg.substr(0, eq);
        value = arg.substr(eq + 1);
        has_inline = true;
      }
      if (value_options.count(name)) {
        if (!has_inline) {
          if (i + 1 >= argc) throw UsageError("uavsim " + cmd + ": " + name + " needs a value");
          value = argv[++i];
        }
        a.values[name].push_back(value);
      } else if (flag_options.count(name) && !has_inline) {
        a.flags.insert(name);
      } else {
        throw UsageError("uavsim " + cmd + ": unknown option '" + arg + "' (see uavsim " + cmd +
                         " --help)");
      }
    } else {
      a.positional.push_back(arg);
    }
  }
  return a;
}

std::vector<std::string> Overrides(const ParsedArgs& a) {
  auto it = a.values.find("--set");
  return it == a.values.end() ? std::vector<std::string>{} : it->second;
}

const std::string& OneScenario(const std::string& cmd, const ParsedArgs& a) {
  if (a.positional.size() != 1)
    throw UsageError("uavsim " + cmd + ": expected one scenario file (see uavsim " + cmd +
                     " --help)");
  return a.positional[0];
}

// --record LIST: camera, lidar, radar and mcap, comma-separated (none: empty).
std::vector<std::string> RecordList(const std::string& cmd, const ParsedArgs& a) {
  std::vector<std::string> record;
  if (auto r = a.Value("--record")) {
    std::stringstream ss(*r);
    std::string m;
    while (std::getline(ss, m, ',')) {
      if (m != "camera" && m != "lidar" && m != "radar" && m != "mcap")
        throw UsageError("uavsim " + cmd +
                         ": --record expects a list of camera, lidar, radar, mcap; got '" + m +
                         "'");
      record.push_back(m);
    }
  }
  return record;
}

// "12 s", "3.4 min", "2.1 h".
std::string Duration(double s) {
  char text[32];
  if (s < 120)
    std::snprintf(text, sizeof text, "%.2g s", s);
  else if (s < 7200)
    std::snprintf(text, sizeof text, "%.2g min", s / 60);
  else
    std::snprintf(text, sizeof text, "%.3g h", s / 3600);
  return text;
}

// A recording that would not fit the output's file system is refused
// before anything is made.
void RequireRoomToRecord(const uavsim::sim::Scenario& s, const uavsim::sim::RunOptions& o) {
  if (o.record.empty()) return;
  const double bytes = uavsim::sim::EstimateRecordBytes(s, o.record);
  const double free = uavsim::sim::FreeBytesFor(o.out_dir);
  if (free < 0 || bytes <= free) return;
  char text[256];
  std::snprintf(text, sizeof text,
                "uavsim run: --record would write up to %.3g bytes; the file system of %s has "
                "%.3g free",
                bytes, o.out_dir.c_str(), free);
  throw UsageError(text);
}

int Validate(int argc, char** argv) {
  const ParsedArgs a =
      Parse("validate", argc, argv, 2, {"--set", "--record"}, {"--quiet", "--resolved", "--help"});
  if (a.Has("--help")) return std::cout << kValidateHelp, kExitOk;
  if (a.positional.empty())
    throw UsageError("uavsim validate: expected a scenario file (see uavsim validate --help)");
  if (a.Has("--resolved") && a.positional.size() != 1)
    throw UsageError("uavsim validate: --resolved prints one scenario: give one file");
  const std::vector<std::string> record = RecordList("validate", a);
  // Each file on its own: a bad one gets its line on stderr and the rest are
  // still checked; the exit code is 2 if any was bad.
  int exit_code = kExitOk;
  for (const std::string& file : a.positional) {
    try {
      const uavsim::sim::Scenario s = uavsim::sim::LoadScenario(file, Overrides(a));
      uavsim::sim::CheckTrainedModel(s, file, a.Has("--quiet"));
      if (a.Has("--resolved")) std::cout << uavsim::sim::ResolvedJson(s).dump(2) << "\n";
      if (!a.Has("--quiet") && !a.Has("--resolved")) {
        const auto e = uavsim::sim::EstimateResources(s);
        std::printf(
            "%s: ok (%zu UAV%s, %zu node%s, %g s simulated, %.3g rays per simulated second; "
            "about %s of wall time here",
            file.c_str(), s.uavs.size(), s.uavs.size() == 1 ? "" : "s", s.nodes.size(),
            s.nodes.size() == 1 ? "" : "s", s.duration_s, e.rays_per_s,
            Duration(uavsim::sim::EstimateWallSeconds(s)).c_str());
        if (!record.empty())
          std::printf("; --record writes at most %.3g bytes",
                      uavsim::sim::EstimateRecordBytes(s, record));
        std::printf(")\n");
        std::fflush(stdout);
      }
    } catch (const uavsim::core::ConfigError& e) {
      if (a.positional.size() == 1) throw;
      std::cerr << e.what() << std::endl;
      exit_code = kExitBadInput;
    }
  }
  return exit_code;
}

// Where the time went, on a terminal: the three largest parts of the
// run's profile_s (metrics.json has them all).
void PrintTopParts(const uavsim::sim::RunSummary& summary) {
  std::vector<std::pair<std::string, double>> parts = summary.profile_s;
  std::stable_sort(parts.begin(), parts.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  if (parts.empty() || summary.wall_s <= 0.0) return;
  std::printf("time:");
  for (std::size_t i = 0; i < parts.size() && i < 3; ++i)
    std::printf("%s %s %.1f s (%.0f %%)", i ? "," : "", parts[i].first.c_str(), parts[i].second,
                100.0 * parts[i].second / summary.wall_s);
  std::printf(" (profile_s in metrics.json)\n");
}

int Run(int argc, char** argv) {
  const ParsedArgs a =
      Parse("run", argc, argv, 2, {"--out", "--seed", "--duration", "--record", "--set"},
            {"--quiet", "--force", "--verbose", "--help"});
  if (a.Has("--help")) return std::cout << kRunHelp, kExitOk;
  g_verbose = a.Has("--verbose");
  const std::string& file = OneScenario("run", a);
  std::vector<std::string> overrides = Overrides(a);
  if (auto seed = a.Value("--seed")) {
    if (seed->empty() || seed->find_first_not_of("0123456789") != std::string::npos ||
        seed->size() > 19)
      throw UsageError("uavsim run: --seed expects a non-negative integer, got '" + *seed + "'");
    overrides.push_back("/seed=" + *seed);
  }
  if (auto d = a.Value("--duration")) {
    char* end = nullptr;
    const double v = std::strtod(d->c_str(), &end);
    if (d->empty() || *end != '\0' || !(v > 0))
      throw UsageError("uavsim run: --duration expects a positive number of seconds, got '" + *d +
                       "'");
    overrides.push_back("/duration_s=" + *d);
  }
  uavsim::sim::RunOptions o;
  o.quiet = a.Has("--quiet");
  o.force = a.Has("--force");
  o.scenario_file = file;
  o.record = RecordList("run", a);
  const uavsim::sim::Scenario s = uavsim::sim::LoadScenario(file, overrides);
  uavsim::sim::CheckTrainedModel(s, file, a.Has("--quiet"));  // what validate checks, first
  o.out_dir = a.Value("--out").value_or("runs/" + s.name + "-s" + std::to_string(s.seed));
  RequireRoomToRecord(s, o);
  const auto summary = uavsim::sim::RunScenario(s, o);
  if (!o.quiet) {
    std::printf("%s: %g s simulated in %.3f s (%.3gx real time); truth.csv %zu rows; frames",
                o.out_dir.c_str(), summary.sim_s, summary.wall_s,
                summary.wall_s > 0 ? summary.sim_s / summary.wall_s : 0.0, summary.truth_rows);
    for (const auto& [m, n] : summary.frames)
      std::printf(" %s %llu", m.c_str(), static_cast<unsigned long long>(n));
    std::printf("\n");
    if (!summary.rmse_m.empty()) {
      std::printf("RMSE (m):");
      for (const auto& [method, rmse] : summary.rmse_m) {
        if (rmse)
          std::printf(" %s %.3f", method.c_str(), *rmse);
        else
          std::printf(" %s n/a", method.c_str());
      }
      std::printf("\n");
    }
    if (!summary.rmse_common_m.empty()) {
      std::printf("RMSE (m) over the %llu windows every method estimated:",
                  static_cast<unsigned long long>(summary.common_windows));
      for (const auto& [method, rmse] : summary.rmse_common_m)
        std::printf(" %s %.3f", method.c_str(), rmse);
      std::printf("\n");
    }
    if (::isatty(STDOUT_FILENO)) PrintTopParts(summary);
  }
  return kExitOk;
}

std::uint64_t UnsignedOption(const std::string& cmd, const std::string& name, const std::string& v,
                             std::uint64_t max) {
  if (v.empty() || v.size() > 19 || v.find_first_not_of("0123456789") != std::string::npos ||
      std::stoull(v) > max)
    throw UsageError("uavsim " + cmd + ": " + name + " expects an integer from 0 to " +
                     std::to_string(max) + ", got '" + v + "'");
  return std::stoull(v);
}

// A number in [lo, hi]; `what` says what is expected ("seconds from 1 to 3600").
double NumberOption(const std::string& cmd, const std::string& name, const std::string& v,
                    double lo, double hi, const std::string& what) {
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0' || !(x >= lo && x <= hi))
    throw UsageError("uavsim " + cmd + ": " + name + " expects " + what + ", got '" + v + "'");
  return x;
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

int Train(int argc, char** argv) {
  std::set<std::string> value_options{
      "--out",   "--seed",           "--episodes",   "--episode-s", "--threads",  "--jobs",
      "--set",   "--data",           "--bottleneck", "--head",      "--config",   "--config-set",
      "--split", "--train-episodes", "--variant",    "--encoders",  "--data-seed"};
  const auto refuse_replaced = [](const std::string& flag) {
    const auto it = ReplacedTrainFlags().find(flag);
    if (it == ReplacedTrainFlags().end()) return;
    const std::string& keys = it->second;
    throw UsageError("uavsim train: " + flag + " was replaced by the training config key" +
                     (keys.find(" and ") == std::string::npos ? " " : "s ") + keys +
                     " (--config FILE or --config-set /" + keys.substr(0, keys.find(' ')) +
                     "=VALUE; see uavsim train --help)");
  };
  // Parsed as value options so that they are refused by name below (and
  // refused by name when last, where Parse would ask for their value).
  for (const auto& [flag, keys] : ReplacedTrainFlags()) value_options.insert(flag);
  if (argc > 2) refuse_replaced(argv[argc - 1]);
  const ParsedArgs a = Parse("train", argc, argv, 2, value_options,
                             {"--quick", "--quiet", "--force", "--wait", "--help"});
  if (a.Has("--help")) return std::cout << kTrainHelp << TrainVariantsHelp(), kExitOk;
  for (const auto& [flag, keys] : ReplacedTrainFlags())
    if (a.Has(flag)) refuse_replaced(flag);
  const std::string& file = OneScenario("train", a);
  uavsim::sim::TrainCommand c;
  c.scenario_file = file;
  c.quick = a.Has("--quick");
  c.quiet = a.Has("--quiet");
  c.force = a.Has("--force");
  c.data_file = a.Value("--data").value_or("");
  c.wait = a.Has("--wait");
  if (auto v = a.Value("--seed")) c.seed = UnsignedOption("train", "--seed", *v, ~0ull >> 1);
  if (auto v = a.Value("--data-seed"))
    c.data_seed = UnsignedOption("train", "--data-seed", *v, ~0ull >> 1);
  if (auto v = a.Value("--episodes"))
    c.episodes = static_cast<int>(UnsignedOption("train", "--episodes", *v, 100000));
  if (auto v = a.Value("--threads"))
    c.threads = static_cast<int>(UnsignedOption("train", "--threads", *v, 256));
  if (auto v = a.Value("--jobs"))
    c.jobs = static_cast<int>(UnsignedOption("train", "--jobs", *v, 1024));
  if (auto v = a.Value("--episode-s"))
    c.episode_s = NumberOption("train", "--episode-s", *v, 1.0, 3600.0, "seconds from 1 to 3600");
  // --bottleneck mlp is the older spelling of --variant mlp_bottleneck.
  const bool mlp_flag = a.Value("--bottleneck") && *a.Value("--bottleneck") == "mlp";
  const std::string variant_name =
      a.Value("--variant").value_or(mlp_flag ? "mlp_bottleneck" : "paper");
  const uavsim::pipeline::Variant* variant = uavsim::pipeline::FindVariant(variant_name);
  if (!variant)
    throw UsageError("uavsim train: --variant expects one of " + uavsim::pipeline::VariantNames() +
                     ", got '" + variant_name + "'");
  c.variant = variant_name;
  c.mlp_bottleneck = variant->mlp_bottleneck;
  if (variant_name != "paper") c.anchored_head = false;  // ours extends the paper's design only
  if (variant_name != "paper" && a.Value("--head") && *a.Value("--head") != "paper" &&
      *a.Value("--head") != "none")
    throw UsageError("uavsim train: --variant " + variant_name +
                     " trains the paper's head only (--head paper); the anchored head "
                     "extends the paper variant");
  if (a.Value("--bottleneck") && variant->mlp_bottleneck != mlp_flag)
    throw UsageError("uavsim train: --bottleneck " + *a.Value("--bottleneck") +
                     " contradicts --variant " + variant_name +
                     " (--bottleneck mlp is --variant mlp_bottleneck)");
  if (auto v = a.Value("--encoders")) c.encoders_dir = *v;  // checked against the variant
  if (auto v = a.Value("--bottleneck")) {
    if (*v != "ib" && *v != "mlp")
      throw UsageError("uavsim train: --bottleneck expects ib or mlp, got '" + *v + "'");
  }
  if (auto v = a.Value("--head")) {
    if (*v != "anchored" && *v != "paper" && *v != "both" && *v != "none")
      throw UsageError("uavsim train: --head expects both, paper, anchored or none, got '" + *v +
                       "'");
    c.paper_head = *v == "paper" || *v == "both";
    c.anchored_head = (*v == "anchored" || *v == "both") && variant_name == "paper";
  }
  if (auto v = a.Value("--split")) {
    if (*v != "trajectory" && *v != "frame")
      throw UsageError("uavsim train: --split expects trajectory or frame, got '" + *v + "'");
    c.split = *v == "frame" ? uavsim::pipeline::DataSplit::kFrame
                            : uavsim::pipeline::DataSplit::kTrajectory;
  }
  if (auto v = a.Value("--train-episodes"))
    c.train_episodes = static_cast<int>(UnsignedOption("train", "--train-episodes", *v, 100000));
  if ((a.Value("--episodes") && c.episodes < 3) || (a.Value("--threads") && c.threads < 1) ||
      c.jobs < 1)
    throw UsageError(
        "uavsim train: --episodes needs at least 3 (training, validation, test), --threads and "
        "--jobs at least 1");
  const auto config_sets = a.values.find("--config-set");
  c.training = uavsim::sim::ResolveTrainingConfig(
      c.quick, a.Value("--config").value_or(""),
      config_sets == a.values.end() ? std::vector<std::string>{} : config_sets->second, variant);
  c.command_line = "uavsim";
  for (int i = 1; i < argc; ++i) c.command_line += " " + std::string(argv[i]);
  uavsim::sim::Scenario s = uavsim::sim::LoadScenario(file, Overrides(a));
  uavsim::sim::ApplyVariantNodes(*variant, s);  // e.g. raw: "without preprocessing"
  c.out_dir = a.Value("--out").value_or("models/" + s.name +
                                        (variant_name == "paper" ? "" : "-" + variant_name));
  const std::optional<uavsim::pipeline::TrainReport> report = uavsim::sim::RunTraining(s, c);
  if (!report) return kExitOk;  // an MPI rank that only simulated episodes
  const uavsim::pipeline::TrainReport& r = *report;
  if (!c.quiet) {
    for (const auto& st : r.stages)
      std::printf(
          "%-15s %5zu train %5zu val  epochs %3d (best %3d)  val loss %.4g -> %.4g  %.0f s\n",
          st.name.c_str(), st.train_items, st.validation_items, st.epochs, st.best_epoch,
          st.initial_validation_loss, st.best_validation_loss, st.seconds);
    for (const auto& [method, ev] : r.test) {
      std::printf("held-out RMSE of %s (m):", method.c_str());
      for (const auto& [k, v] : ev.rmse_m) std::printf(" %s %.3f", k.c_str(), v);
      std::printf("\n");
    }
    if (!r.test_decoder.empty()) {
      std::printf("held-out RMSE of each node's IB decoder alone, no fusion (m):");
      for (const auto& [modality, d] : r.test_decoder)
        std::printf(" %s %.3f (%zu obs.)", modality.c_str(), d.rmse_m, d.observations);
      std::printf("\n");
      // The information limit beside it: the same on-target observations'
      // centroid (the camera: its ray at the true range).
      for (const auto& [modality, d] : r.test_decoder)
        std::printf(
            "  %-6s on target %.3f (%zu obs.), centroid of the same %.3f; off target %.3f (%zu "
            "obs.)\n",
            modality.c_str(), d.on_target_rmse_m, d.on_target, d.centroid_on_target_m,
            d.off_target_rmse_m, d.off_target);
      std::printf("validation on target (what stage-1 settings are chosen on):");
      for (const auto& [modality, d] : r.validation_decoder)
        std::printf(" %s %.3f vs centroid %.3f (%zu obs.)", modality.c_str(), d.on_target_rmse_m,
                    d.centroid_on_target_m, d.on_target);
      std::printf("\n");
      std::printf("held-out observations holding the target (of those sent):");
      for (const auto& [modality, weathers] : r.test_sent)
        for (const auto& [weather, c] : weathers)
          std::printf(" %s/%s %zu of %zu", modality.c_str(), weather.c_str(), c.holding_target,
                      c.sent);
      std::printf("\n");
    }
    if (r.test_common.size() > 1) {
      std::size_t fewest = ~std::size_t{0}, most = 0;
      for (const auto& [method, ev] : r.test) {
        fewest = std::min(fewest, ev.windows.at("all"));
        most = std::max(most, ev.windows.at("all"));
      }
      std::printf(
          "held-out RMSE on the windows every method counted (m; all: %zu windows, each method "
          "alone %zu to %zu):\n",
          r.test_common.begin()->second.windows.at("all"), fewest, most);
      for (const auto& [method, ev] : r.test_common) {
        std::printf("  %-16s", method.c_str());
        for (const auto& [k, v] : ev.rmse_m) std::printf(" %s %.3f", k.c_str(), v);
        std::printf("\n");
      }
    }
    std::printf("model written to %s (use: --set /pipeline/model=%s)\n", c.out_dir.c_str(),
                c.out_dir.c_str());
  }
  return kExitOk;
}

int Dataset(int argc, char** argv) {
  const ParsedArgs a = Parse(
      "dataset", argc, argv, 2,
      {"--out", "--episodes", "--episode-s", "--seed", "--jobs", "--model", "--data", "--set"},
      {"--force", "--quiet", "--help"});
  if (a.Has("--help")) return std::cout << kDatasetHelp, kExitOk;
  const std::string& file = OneScenario("dataset", a);
  uavsim::sim::DatasetCommand c;
  c.scenario_file = file;
  c.force = a.Has("--force");
  c.quiet = a.Has("--quiet");
  if (!a.Value("--out") || a.Value("--out")->empty())
    throw UsageError("uavsim dataset: --out FILE.h5 is required (see uavsim dataset --help)");
  c.out_file = *a.Value("--out");
  c.model = a.Value("--model").value_or("");
  c.data_file = a.Value("--data").value_or("");
  if (auto v = a.Value("--seed")) c.seed = UnsignedOption("dataset", "--seed", *v, ~0ull >> 1);
  if (auto v = a.Value("--episodes"))
    c.episodes = static_cast<int>(UnsignedOption("dataset", "--episodes", *v, 100000));
  if (auto v = a.Value("--jobs"))
    c.jobs = static_cast<int>(UnsignedOption("dataset", "--jobs", *v, 1024));
  if (auto v = a.Value("--episode-s"))
    c.episode_s = NumberOption("dataset", "--episode-s", *v, 1.0, 3600.0, "seconds from 1 to 3600");
  if ((a.Value("--episodes") && c.episodes < 1) || c.jobs < 1)
    throw UsageError("uavsim dataset: --episodes and --jobs need at least 1");
  const uavsim::sim::Scenario s = uavsim::sim::LoadScenario(file, Overrides(a));
  const std::optional<uavsim::sim::DatasetSummary> r = uavsim::sim::RunDatasetExport(s, c);
  if (!r || c.quiet) return kExitOk;  // an MPI rank that only simulated episodes
  std::size_t frames = 0;
  for (std::size_t n : r->frames) frames += n;
  std::printf(
      "%s: %zu episodes of %g s, %zu frames (camera %zu, lidar %zu, radar %zu; %.1f %% on time)",
      c.out_file.c_str(), r->episodes, r->episode_s, frames, r->frames[0], r->frames[1],
      r->frames[2],
      frames ? 100.0 * static_cast<double>(r->on_time) / static_cast<double>(frames) : 0.0);
  if (r->latent_dim > 0)
    std::printf(", latents of %lld values", static_cast<long long>(r->latent_dim));
  std::printf(", %.1f MB\n", static_cast<double>(r->bytes) / 1e6);
  return kExitOk;
}

void PrintSweepOutcome(const std::string& dir, const uavsim::sim::SweepOutcome& r) {
  std::printf("%s: %zu points: %zu run now, %zu already done, %zu failed", dir.c_str(), r.points,
              r.ran, r.already_done, r.failed);
  if (r.missing > 0) std::printf(", %zu left to other shards", r.missing);
  std::printf("\n");
  if (r.reported)
    std::printf("%s/summary.csv, %s/aggregate.csv, %s/plots/ and %s/report.html written\n",
                dir.c_str(), dir.c_str(), dir.c_str(), dir.c_str());
  else if (r.missing > 0 && r.failed == 0)
    std::printf("when every shard is done: uavsim sweep merge %s\n", dir.c_str());
}

int Sweep(int argc, char** argv) {
  const ParsedArgs a = Parse("sweep", argc, argv, 2, {"--out", "--jobs", "--shard"},
                             {"--quiet", "--wait", "--help"});
  if (a.Has("--help")) return std::cout << kSweepHelp, kExitOk;
  const bool quiet = a.Has("--quiet");
  if (!a.positional.empty() && a.positional[0] == "merge") {
    if (a.positional.size() != 2 || a.Has("--out") || a.Has("--jobs") || a.Has("--shard"))
      throw UsageError("uavsim sweep merge: expected one sweep folder (see uavsim sweep --help)");
    const auto r = uavsim::sim::MergeSweep(a.positional[1]);
    for (const std::string& w : r.warnings) std::cerr << "uavsim: warning: " << w << "\n";
    if (!quiet) PrintSweepOutcome(a.positional[1], r);
    return kExitOk;
  }
  if (a.positional.size() != 1)
    throw UsageError("uavsim sweep: expected one sweep spec file (see uavsim sweep --help)");
  uavsim::sim::SweepOptions o;
  o.quiet = quiet;
  o.wait = a.Has("--wait");
  if (auto v = a.Value("--jobs"))
    o.jobs = static_cast<int>(UnsignedOption("sweep", "--jobs", *v, 1024));
  if (o.jobs < 1) throw UsageError("uavsim sweep: --jobs needs at least 1");
  if (auto v = a.Value("--shard")) {
    const auto slash = v->find('/');
    const std::string i = slash == std::string::npos ? *v : v->substr(0, slash);
    const std::string n = slash == std::string::npos ? "" : v->substr(slash + 1);
    if (slash == std::string::npos || i.empty() || n.empty() ||
        i.find_first_not_of("0123456789") != std::string::npos ||
        n.find_first_not_of("0123456789") != std::string::npos || i.size() > 6 || n.size() > 6 ||
        std::stoi(n) < 1 || std::stoi(i) >= std::stoi(n))
      throw UsageError("uavsim sweep: --shard expects I/N with 0 <= I < N, got '" + *v + "'");
    o.shard_index = std::stoi(i);
    o.shard_count = std::stoi(n);
  }
  const uavsim::sim::SweepSpec spec = uavsim::sim::LoadSweepSpec(a.positional[0], quiet);
  o.out_dir = a.Value("--out").value_or("runs/" + spec.name);
  const auto r = uavsim::sim::RunSweep(spec, o);
  if (r.mpi_worker) return r.failed ? kExitFailure : kExitOk;
  for (const std::string& w : r.warnings) std::cerr << "uavsim: warning: " << w << "\n";
  if (!quiet) PrintSweepOutcome(o.out_dir, r);
  if (r.failed) {
    std::cerr << "uavsim sweep: " << r.failed << " of " << r.points
              << " points failed (messages above); rerun the same command to retry them\n";
    return kExitFailure;
  }
  return kExitOk;
}

int Reproduce(int argc, char** argv) {
  const ParsedArgs a = Parse("reproduce", argc, argv, 2,
                             {"--scenario", "--out", "--jobs", "--seeds", "--episodes", "--set"},
                             {"--quick", "--quiet", "--wait", "--help"});
  if (a.Has("--help")) return std::cout << kReproduceHelp, kExitOk;
  if (!a.positional.empty())
    throw UsageError("uavsim reproduce: unexpected argument '" + a.positional[0] +
                     "' (the scenario goes after --scenario; see uavsim reproduce --help)");
  uavsim::sim::ReproduceOptions o;
  o.wait = a.Has("--wait");
  o.quick = a.Has("--quick");
  o.quiet = a.Has("--quiet");
  const std::string scenario = a.Value("--scenario").value_or("city");
  o.scenario_file = scenario == "city"   ? "scenarios/default.json"
                    : scenario == "twin" ? "scenarios/mmaud_twin.json"
                                         : scenario;
  if (auto v = a.Value("--jobs"))
    o.jobs = static_cast<int>(UnsignedOption("reproduce", "--jobs", *v, 1024));
  if (auto v = a.Value("--seeds"))
    o.seeds = static_cast<int>(UnsignedOption("reproduce", "--seeds", *v, 100));
  if (auto v = a.Value("--episodes"))
    o.episodes = static_cast<int>(UnsignedOption("reproduce", "--episodes", *v, 100000));
  if (o.jobs < 1 || (a.Value("--seeds") && o.seeds < 1) ||
      (a.Value("--episodes") && o.episodes < 3))
    throw UsageError("uavsim reproduce: --jobs and --seeds need at least 1, --episodes at least 3");
  o.command_line = "uavsim";
  for (int i = 1; i < argc; ++i) o.command_line += " " + std::string(argv[i]);
  const uavsim::sim::Scenario s = uavsim::sim::LoadScenario(o.scenario_file, Overrides(a));
  o.out_dir = a.Value("--out").value_or("runs/reproduce-" + s.name + (o.quick ? "-quick" : ""));
  const uavsim::sim::ReproduceOutcome r = uavsim::sim::RunReproduce(s, o);
  if (r.mpi_worker) return r.failed ? kExitFailure : kExitOk;
  for (const std::string& w : r.warnings) std::cerr << "uavsim: warning: " << w << "\n";
  if (r.failed) {
    std::cerr << "uavsim reproduce: " << r.failed << " of " << r.arms
              << " trainings failed or did not run (messages above); rerun the same command "
                 "to retry them\n";
    return kExitFailure;
  }
  if (!o.quiet)
    std::printf("%zu trainings (%zu already done, %zu now) in %.0f s; report: %s/report.html\n",
                r.arms, r.already_done, r.ran, r.wall_s, o.out_dir.c_str());
  return kExitOk;
}

int Report(int argc, char** argv) {
  const ParsedArgs a = Parse("report", argc, argv, 2, {}, {"--quiet", "--help"});
  if (a.Has("--help")) return std::cout << kReportHelp, kExitOk;
  if (a.positional.size() != 1)
    throw UsageError(
        "uavsim report: expected one run directory, sweep folder or reproduction (see uavsim "
        "report --help)");
  const std::string dir = a.positional[0];
  namespace fs = std::filesystem;
  std::error_code ec;
  std::vector<std::string> warnings;
  if (fs::is_regular_file(fs::path(dir) / "sweep.json", ec)) {
    warnings = uavsim::sim::MergeSweep(dir).warnings;
  } else if (fs::is_regular_file(fs::path(dir) / "metrics.json", ec) &&
             fs::is_regular_file(fs::path(dir) / "manifest.json", ec)) {
    try {
      warnings = uavsim::results::WriteRunReport(dir);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("uavsim report: ") + e.what());
    }
  } else if (fs::is_regular_file(fs::path(dir) / "claims.csv", ec) &&
             fs::is_regular_file(fs::path(dir) / "report.md", ec)) {
    uavsim::sim::RedrawReproduceReport(dir);
  } else {
    throw UsageError("uavsim report: " + dir +
                     ": neither a run directory (no metrics.json and manifest.json), a sweep "
                     "folder (no sweep.json) nor a reproduction (no claims.csv and report.md)");
  }
  for (const std::string& w : warnings) std::cerr << "uavsim: warning: " << w << "\n";
  if (!a.Has("--quiet")) std::printf("%s/report.html written\n", dir.c_str());
  return kExitOk;
}

int Bench(int argc, char** argv) {
  const ParsedArgs a = Parse("bench", argc, argv, 2, {}, {"--quiet", "--help"});
  if (a.Has("--help")) return std::cout << kBenchHelp, kExitOk;
  if (a.positional.size() > 1)
    throw UsageError("uavsim bench: expected at most one target (see uavsim bench --help)");
  const std::string what = a.positional.empty() ? "all" : a.positional[0];
  const bool quiet = a.Has("--quiet");
  const std::vector<std::pair<std::string, std::function<int()>>> targets{
      {"raycast", [&] { return uavsim::sim::BenchRaycast(quiet, std::cout); }},
      {"radar", [&] { return uavsim::sim::BenchRadar(quiet, std::cout); }},
      {"events", [&] { return uavsim::sim::BenchEvents(quiet, std::cout); }},
      {"link", [&] { return uavsim::sim::BenchLink(quiet, std::cout); }},
      {"beam", [&] { return uavsim::sim::BenchBeam(quiet, std::cout); }},
      {"pipeline", [&] { return uavsim::sim::BenchPipeline(quiet, std::cout); }},
      {"noise", [&] { return uavsim::sim::BenchNoise(quiet, std::cout); }},
      {"flops", [&] { return uavsim::sim::BenchFlops(quiet, std::cout); }},
  };
  int rc = kExitOk;
  bool found = false;
  for (const auto& [name, run] : targets) {
    if (what != "all" && what != name) continue;
    found = true;
    if (what == "all") std::cout << "== " << name << "\n";
    rc = std::max(rc, run());
  }
  if (!found)
    throw UsageError("uavsim bench: unknown target '" + what +
                     "' (raycast, radar, events, link, beam, pipeline, noise, flops or all)");
  return rc;
}

int Main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << kMainHelp;
    return kExitBadInput;
  }
  const std::string cmd = argv[1];
  if (cmd == "--help" || cmd == "-h" || cmd == "help") return std::cout << kMainHelp, kExitOk;
  if (cmd == "--version") {
    std::cout << "uavsim " << uavsim::sim::Version();
    if (*uavsim::sim::GitHash()) std::cout << " (" << uavsim::sim::GitHash() << ")";
    std::cout << "\n";
    return kExitOk;
  }
  if (cmd == "validate") return Validate(argc, argv);
  if (cmd == "run") return Run(argc, argv);
  if (cmd == "bench") return Bench(argc, argv);
  if (cmd == "sweep") return Sweep(argc, argv);
  if (cmd == "train") return Train(argc, argv);
  if (cmd == "dataset") return Dataset(argc, argv);
  if (cmd == "reproduce") return Reproduce(argc, argv);
  if (cmd == "report") return Report(argc, argv);
  throw UsageError("uavsim: unknown command '" + cmd + "' (see uavsim --help)");
}

// The handlers go in before any shared library's initialisers run
// (LibTorch's take about half a second, more on a loaded machine): a
// SIGINT or SIGTERM from a command's first moments gets exit 130 and the
// documented line, not the default action's 143. Only the dynamic
// loader's work comes before a program's .preinit_array; the launcher
// (launcher.cpp) blocks the two signals over it, so they are unblocked
// here, once the handlers are in: one that came meanwhile is delivered now.
void InstallHandlersFirst(int, char**, char**) {
  uavsim::core::InstallInterruptHandlers();
  sigset_t termination;
  sigemptyset(&termination);
  sigaddset(&termination, SIGINT);
  sigaddset(&termination, SIGTERM);
  sigprocmask(SIG_UNBLOCK, &termination, nullptr);
}
__attribute__((section(".preinit_array"),
               used)) void (*const kInstallHandlersFirst)(int, char**,
                                                          char**) = InstallHandlersFirst;

}  // namespace

int main(int argc, char** argv) {
  try {
    uavsim::core::InstallInterruptHandlers();  // again: a library's initialiser may have reset them
    uavsim::core::ThrowIfInterrupted();        // a request during the libraries' initialisers
    const int rc = Main(argc, argv);
    // A request the command did not poll for (it came during its last
    // steps): answered like any other.
    uavsim::core::ThrowIfInterrupted();
    return rc;
  } catch (const uavsim::core::ConfigError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const UsageError& e) {
    std::cerr << e.what() << "\n";
    return kExitBadInput;
  } catch (const uavsim::core::Interrupted&) {
    std::cerr << "uavsim: interrupted; nothing half-written is left under a final name\n";
    return kExitInterrupted;
  } catch (const std::bad_alloc&) {
    std::cerr << "uavsim: out of memory\n";
    return kExitFailure;
  } catch (const uavsim::pipeline::ScriptedEdgeFailure& e) {
    std::cerr << "uavsim: " << e.what() << "\n";
    if (g_verbose) std::cerr << e.traceback() << "\n";
    return kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "uavsim: " << e.what() << "\n";
    return kExitFailure;
  }
}
