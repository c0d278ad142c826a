// `uavsim dataset` as typed: its usage, options and help (its body:
// apps/cli/dataset.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

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
          RunDatasetCommand};
}

}  // namespace uavsim::cli
