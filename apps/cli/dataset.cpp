// `uavsim dataset`: the training episodes as one HDF5 file.
#include <cstdio>
#include <iostream>

#include "apps/cli/cli.h"
#include "apps/dataset/dataset_export.h"
#include "core/error.h"
#include "sim/scenario.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

const char* kHelp =
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

int Dataset(const ParsedArgs& a, int, char**) {
  const std::string& file = OneScenario("dataset", a);
  sim::DatasetCommand c;
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
  const sim::Scenario s = sim::LoadScenario(file, Overrides(a));
  const std::optional<sim::DatasetSummary> r = sim::RunDatasetExport(s, c);
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

std::string Help() { return kHelp; }

}  // namespace

Command DatasetCommand() {
  return {"dataset",
          "dataset SCENARIO.json",
          "export the training simulation's episodes to HDF5",
          {{"--out", true},
           {"--episodes", true},
           {"--episode-s", true},
           {"--seed", true},
           {"--jobs", true},
           {"--model", true},
           {"--data", true},
           {"--set", true},
           {"--force", false}},
          Help,
          Dataset};
}

}  // namespace uavsim::cli
